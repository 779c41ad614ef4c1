// Runs the Khronos glTF validator on each file and prints one JSON object per file, one a line:
// {"file", "errors", "warnings", "infos", "hints", "messages": [{code, severity, message, pointer}]}.
// Usage: node tools/gltf_validate.mjs TOOLS_DIR FILE...   (TOOLS_DIR from tools/ensure_test_tools.sh)
import { createRequire } from "node:module";
import { readFile } from "node:fs/promises";
import path from "node:path";

const [toolsDir, ...files] = process.argv.slice(2);
const require = createRequire(path.join(path.resolve(toolsDir), "package.json"));
const validator = require("gltf-validator");

for (const file of files) {
  const bytes = new Uint8Array(await readFile(file));
  const report = await validator.validateBytes(bytes, {
    uri: path.basename(file),
    maxIssues: 100,
    externalResourceFunction: (uri) =>
      readFile(path.join(path.dirname(file), decodeURIComponent(uri))).then((b) => new Uint8Array(b)),
  });
  const i = report.issues;
  console.log(JSON.stringify({
    file,
    validator: report.validatorVersion,
    errors: i.numErrors,
    warnings: i.numWarnings,
    infos: i.numInfos,
    hints: i.numHints,
    messages: i.messages.map((m) => ({ code: m.code, severity: m.severity, message: m.message, pointer: m.pointer })),
  }));
}
