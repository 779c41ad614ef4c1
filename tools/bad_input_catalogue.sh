#!/usr/bin/env bash
# The catalogue of bad input of issue 9: every kind of bad input, fault and trap the tests cover
# (tests/bad_input.rs, hostile_*.rs, interrupt.rs, resume.rs and the refusals of drape.rs, fit.rs,
# garment.rs, batch.rs, gltf.rs), each made afresh in a temporary folder and given to drapekit.
# Prints a markdown document: per kind its class in the issue, the command, the exit status and
# the first line of stderr (with the next when the first ends in ':', a list of problems); for
# a run that must succeed or leave files alone, what was checked. docs/bad-input.md is its output:
#   tools/bad_input_catalogue.sh > docs/bad-input.md
# With --memory it also measures peak memory (/usr/bin/time -v) on the largest inputs: a 1 GB
# file of blank lines (as OBJ and as vertex triples, made in /tmp and deleted), the largest
# real meshes, a 100,000-corner outline, the refused huge requests, a fit and a garment on the
# real body (needs about 1.2 GB of free disk in /tmp and ten minutes).
# Usage: tools/bad_input_catalogue.sh [--memory] [DRAPEKIT]   (default: the release build)
# Kinds that need ../shared/realdata are left out, and said so, when it is missing.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
memory=false
if [[ ${1:-} == --memory ]]; then
    memory=true
    shift
fi
if [[ -n ${1:-} ]]; then
    exe=$(realpath "$1")
else
    (cd "$here" && cargo build --release --quiet)
    exe=${CARGO_TARGET_DIR:-$here/target}/release/drapekit
fi
data=$here/../shared/realdata
[[ -d $data ]] && data=$(cd "$data" && pwd) || data=
fixtures=$here/fixtures
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
rows=$work/rows.md
: >"$rows"
n=0
row=0
missing=()

# new: a fresh, empty case folder, made the current one.
new() {
    n=$((n + 1))
    d=$work/case$n
    mkdir -p "$d"
    cd "$d"
}

# clean TEXT: the message as the table shows it (case folder and work folder named shortly,
# pipes escaped, at most 400 characters).
clean() {
    local s=${1//"$d/"/}
    s=${s//"$d"/.}
    s=${s//"$exe"/drapekit}
    s=${s//"$work"/\$TMP}
    [[ -n $data ]] && s=${s//"$data"/realdata}
    s=${s//"$fixtures"/fixtures}
    s=${s//|/\\|}
    ((${#s} > 400)) && s="${s:0:400}…"
    printf '%s' "$s"
}

# first_line FILE: the first line of FILE, joined with the second when it ends in ':'.
first_line() {
    local a b
    a=$(sed -n 1p "$1")
    if [[ $a == *: ]]; then
        b=$(sed -n 2p "$1" | sed 's/^ *//')
        a="$a $b"
    fi
    printf '%s' "$a"
}

# case CLASS KIND ARGS...: runs drapekit ARGS in the case folder (at most 10 minutes); the row.
# $check, when set, is run after it and its output goes into the row after the kind; $show,
# when set, is a pattern picking the line of stdout shown when stderr says nothing.
case_() {
    local class=$1 kind=$2
    shift 2
    local code=0
    timeout 600 "$exe" "$@" >"$d/.out" 2>"$d/.err" </dev/null || code=$?
    ((code == 124)) && kind="$kind (HUNG: killed after 600 s)"
    local msg
    msg=$(first_line "$d/.err")
    if [[ -z $msg && -n ${show:-} ]]; then
        msg="(stdout) $(grep -m1 -- "$show" "$d/.out" || true)"
    fi
    if [[ -n ${check:-} ]]; then
        kind="$kind; checked: $(eval "$check" 2>&1 | tr '\n' ' ')"
    fi
    local cmd="drapekit"
    local a
    for a in "$@"; do
        [[ ${#a} -gt 80 ]] && a="${a:0:60}…"
        cmd="$cmd $(printf '%q' "$a")"
    done
    row=$((row + 1))
    printf '| %d | %s | %s | `%s` | %d | %s |\n' "$row" "$class" "$(clean "$kind")" \
        "$(clean "$cmd")" "$code" "$(clean "$msg")" >>"$rows"
    check=
    show=
}

# convert_case CLASS KIND FILE CONTENT [FLAGS...]: FILE (printf-escaped CONTENT) converted to out.ply.
convert_case() {
    local class=$1 kind=$2 file=$3 content=$4
    shift 4
    new
    printf "$content" >"$file"
    case_ "$class" "$kind" convert "$file" -o out.ply "$@"
}

# sphere_scene EDITS...: the sphere-drop fixture as s.toml beside its sphere, each edit a
# python str.replace pair FROM=>TO (first occurrence).
edit_scene() {
    local src=$1
    shift
    python3 - "$src" "$@" <<'EOF' >s.toml
import sys
s = open(sys.argv[1]).read()
for e in sys.argv[2:]:
    a, b = e.split("=>", 1)
    a, b = a.encode().decode("unicode_escape"), b.encode().decode("unicode_escape")
    assert a in s, a
    s = s.replace(a, b, 1)
sys.stdout.write(s)
EOF
}
sphere_scene() {
    cp "$fixtures/scenes/sphere_r0.3.obj" .
    edit_scene "$fixtures/scenes/sphere_drop.toml" "$@"
}
FIVE='until_rest = 1e-5            # J of kinetic energy\nmax_steps = 40000=>steps = 5'

# ---------------------------------------------------------------------------------------------
# Other reader errors: mesh files (tests/bad_input.rs, gltf.rs).
R="Other reader errors"
convert_case "$R" "vertex triples: 6 numbers on a line" a.txt '0 0 0 1 0 0\n'
convert_case "$R" "vertex triples: a block of 5 points" b.txt '0 0 0\n1 0 0\n0 1 0\n\n0 0 1\n1 0 1\n0 1 1\n\n0 0 2\n1 0 2\n0 1 2\n1 1 2\n2 2 2\n'
convert_case "$R" "vertex triples: a point left over" c.txt '0 0 0\n1 0 0\n0 1 0\n5 5 5\n'
convert_case "$R" "two tokens that are not numbers (all problems listed)" d.txt '0 0 0\n1 0 x\n0 1 0\n0 0 y\n'
convert_case "$R" "NaN coordinate (OBJ)" e.obj 'v 0 0 0\nv 1 NaN 0\nv 0 1 0\nf 1 2 3\n'
convert_case "$R" "inf coordinate (triples)" f.txt '0 0 0\n1 inf 0\n0 1 0\n'
stl() { # stl DECLARED TRIANGLES [CUT] [NAN]: a binary STL on stdout
    python3 -c '
import struct, sys
decl, tri, cut, nan = int(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3]), sys.argv[4] == "1"
b = b" " * 80 + struct.pack("<I", decl)
for t in range(tri):
    b += bytes(12) + struct.pack("<9f", 0, 0, t, 1, 0, t, 0, 1, t) + bytes(2)
if nan:
    b = b[:100] + struct.pack("<f", float("nan")) + b[104:]
sys.stdout.buffer.write(b[:cut] if cut else b)' "$@"
}
new; stl 4 4 201 0 >g.stl
case_ "$R" "binary STL cut short" convert g.stl -o out.ply
new; stl 2 3 0 0 >h.stl
case_ "$R" "binary STL: triangle count disagrees with the size" convert h.stl -o out.ply
new; stl 1 1 0 1 >i.stl
case_ "$R" "binary STL: NaN coordinate" convert i.stl -o out.ply
convert_case "$R" "ASCII PLY promises 4 vertices, has 3" j.ply 'ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n'
new
python3 -c '
import struct, sys
h = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n"
sys.stdout.buffer.write(h + struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0) + b"\x03" + struct.pack("<3i", 0, 1, 2))' >k.ply
case_ "$R" "binary PLY promises 2 faces, has 1" convert k.ply -o out.ply
convert_case "$R" "PLY without its magic line" l.ply 'format ascii 1.0\nend_header\n'
convert_case "$R" "PLY property of an unknown type" m.ply 'ply\nformat ascii 1.0\nelement vertex 1\nproperty quad x\nend_header\n'
convert_case "$R" "OBJ face index out of range" n.obj 'v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n'
convert_case "$R" "OBJ negative index before any vertex" o.obj 'f -1 -2 -3\nv 0 0 0\n'
convert_case "$R" "OBJ face of two corners" p.obj 'v 0 0 0\nv 1 0 0\nf 1 2\n'
convert_case "$R" "ASCII STL: misspelt keyword" q.stl 'solid x\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n   vertx 0 1 0\n  endloop\n endfacet\nendsolid x\n'
convert_case "$R" "AutoCAD LISP: unbalanced parentheses" r.txt '(0 0 0)\n(1 0 0\n(0 1 0)\n'
convert_case "$R" "empty file" s.stl ''
convert_case "$R" "not a mesh (format unknown)" t.dat 'hello world\nthis is not a mesh\n'
convert_case "$R" "points without faces" u.obj 'v 0 0 0\nv 1 0 0\nv 0 1 0\n'
new
case_ "$R" "input file missing" convert nope.obj -o x.ply
convert_case "$R" "usage: weld tolerance not a number" v.txt '0 0 0\n1 0 0\n0 1 0\n' --weld-tol abc
convert_case "$R" "usage: --to-units without --units" w.txt '0 0 0\n1 0 0\n0 1 0\n' --to-units m
convert_case "$R" "usage: unknown quad split" x.txt '0 0 0\n1 0 0\n0 1 0\n' --quad-split longest
new
printf '0 0 0\n1 0 0\n0 1 0\n' >in.txt
case_ "$R" "unknown output extension" convert in.txt -o out.xyz

# glTF (tests/gltf.rs): a valid sheet written by drapekit, then damaged.
new
printf 'v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nv 2 1 0\nf 1 2 3\nf 1 3 4\nf 2 5 6\nf 2 6 3\n' >sheet.obj
"$exe" convert sheet.obj -o ok.glb >/dev/null 2>&1
"$exe" convert sheet.obj -o base.gltf >/dev/null 2>&1
gltf_dir=$d
python3 -c '
import sys
b = open("ok.glb", "rb").read()
open("cut.glb", "wb").write(b[:-7])
open("magic.glb", "wb").write(b"glTX" + b[4:])
import struct
jl = struct.unpack("<I", b[12:16])[0]
at = 12 + 8 + jl + 8
open("nan.glb", "wb").write(b[:at] + struct.pack("<f", float("nan")) + b[at + 4:])'
for f in cut magic nan; do
    new
    cp "$gltf_dir/$f.glb" .
    case_ "$R" "glTF: $(case $f in cut) echo "binary glTF cut short" ;; magic) echo "binary glTF with a wrong magic" ;; nan) echo "binary glTF with a NaN position" ;; esac)" convert $f.glb -o x.obj
done
gltf_edit() { # gltf_edit NAME KIND PYTHON-EDIT-OF-j
    new
    cp "$gltf_dir"/base* .
    python3 -c "
import json
j = json.load(open('base.gltf'))
$3
json.dump(j, open('$1.gltf', 'w'))"
    case_ "$R" "glTF: $2" convert "$1.gltf" -o x.obj
}
gltf_edit accessor "indices name an accessor that does not exist" 'j["meshes"][0]["primitives"][0]["indices"] = 9'
gltf_edit short "accessor longer than its bufferView" 'j["accessors"][0]["count"] = 10**4'
gltf_edit view "bufferView beyond its buffer" 'j["bufferViews"][-1]["byteOffset"] = 100000'
gltf_edit missing "buffer file missing" 'j["buffers"][0]["uri"] = "missing%20data.bin"'
gltf_edit lines "a primitive of lines" 'j["meshes"][0]["primitives"][0]["mode"] = 1'
gltf_edit cycle "a node that is its own child" 'j["nodes"][0]["children"] = [0]'
gltf_edit draco "a required extension drapekit lacks" 'j["extensionsRequired"] = ["KHR_draco_mesh_compression"]'

# ---------------------------------------------------------------------------------------------
# Other reader errors: scenes (tests/drape.rs).
scene_case() { # scene_case KIND TAIL EDITS...: fixtures/bad_scene_base.toml with its edits and TAIL appended, draped
    local kind=$1 tail=$2
    shift 2
    new
    cp "$fixtures/scenes/sphere_r0.3.obj" .
    edit_scene "$fixtures/bad_scene_base.toml" "$@"
    printf '%s' "$tail" >>s.toml
    case_ "$R" "scene: $kind" drape s.toml -o out
}
SQ='[[-0.4, -0.4], [0.4, -0.4], [0.4, 0.4], [-0.4, 0.4]]'
scene_case "object mesh missing" "" 'sphere_r0.3.obj=>nowhere.obj'
scene_case "outline crosses itself" "" "$SQ=>[[-0.4, -0.4], [0.4, 0.4], [0.4, -0.4], [-0.4, 0.4]]"
scene_case "outline of two points" "" "$SQ=>[[0, 0], [1, 0]]"
scene_case "negative density" $'[fabric.thin]\nbase = "cotton"\ndensity = -0.1\n' 'fabric = "cotton"=>fabric = "thin"'
scene_case "negative step" "" 'dt = 1e-4=>dt = -1e-4'
scene_case "unknown key" "" 'spacing = 0.05=>spacing = 0.05\ncolour = "red"'
scene_case "unknown fabric preset" "" 'fabric = "cotton"=>fabric = "velvet"'
scene_case "unknown unit" "" 'units = "m"=>units = "ft"'
scene_case "pin off the cloth" "" 'fabric = "cotton"=>fabric = "cotton"\npin = [[0.0, 0.9]]'
scene_case "no stop" "" 'steps = 10=>'
scene_case "zero grid cells" $'[collision]\ncells = [0, 5, 5]\n'
scene_case "an implicit-Euler key with the default integrator" "" 'steps = 10=>steps = 10\nnewton_iterations = 3'
scene_case "a projective-dynamics key with leapfrog" "" 'steps = 10=>steps = 10\nintegrator = "leapfrog"\nchebyshev = 0.9'
scene_case "Chebyshev with Anderson" "" 'steps = 10=>steps = 10\nchebyshev = 0.9'
scene_case "strain band out of range" "" 'steps = 10=>steps = 10\nstrain_band = -0.1'
scene_case "strain tolerance out of range" "" 'steps = 10=>steps = 10\nstrain_tolerance = 0'
scene_case "too many correction rounds" "" 'steps = 10=>steps = 10\ncorrections = 11'
scene_case "Anderson history too deep" "" 'steps = 10=>steps = 10\nanderson = 1000'
scene_case "Chebyshev radius out of range" "" 'steps = 10=>steps = 10\nanderson = 0\nchebyshev = 1.0'
scene_case "unknown integrator" "" 'steps = 10=>steps = 10\nintegrator = "verlet"'
scene_case "three problems at once" "" 'dt = 1e-4=>dt = -1' 'sphere_r0.3.obj=>nowhere.obj' 'fabric = "cotton"=>fabric = "velvet"'
new
printf 'v 0 0 0\nv 1 0 0\nv 2 0 0\nv 3 0 0\nf 1 2 3\nf 2 3 4\n' >line.obj
sed 's/sphere_r0.3.obj/line.obj/' "$fixtures/bad_scene_base.toml" >s.toml
case_ "$R" "scene: an object mesh with no surface (every face degenerate)" drape s.toml -o out
new
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n' >broken.obj
sed 's/sphere_r0.3.obj/broken.obj/' "$fixtures/bad_scene_base.toml" >s.toml
case_ "$R" "scene: an object mesh that does not parse" drape s.toml -o out

# Other reader errors: fit inputs (tests/fit.rs).
fit_case() { # fit_case KIND FLAG FILE CONTENT [FLAGS...]
    local kind=$1 flag=$2 file=$3 content=$4
    shift 4
    new
    printf "$content" >"$file"
    case_ "$R" "fit: $kind" fit "$flag" "$file" -o out.obj "$@"
}
fit_case "sections JSON cut short" --sections a.json '{"units": "m", "sections": [{"height": 1, "points": [[0, 0], [1, 0]]\n'
fit_case "sections JSON with a misspelt key" --sections b.json '{"units": "m",\n "sectons": []}'
fit_case "sections JSON height not a number" --sections c.json '{"sections": [{"height": "high", "points": []}]}'
fit_case "sections CSV with a word for a number" --sections d.csv 'height,x,y\n0,0,0\n0,1,0\n0,0,oops\n'
fit_case "measurements with a misspelt key" --measurements e.toml 'units = "cm"\nstature = 170\nbust_grith = 90\n'
fit_case "measurements: stature not a number" --measurements f.toml 'units = "cm"\nstature = "tall"\nbust_girth = 90\nwaist_girth = 70\n'
fit_case "measurements: one girth" --measurements g.toml 'units = "cm"\nstature = 170\nwaist_girth = 70\n'
fit_case "measurements: unknown unit" --measurements h.toml 'units = "cubits"\nstature = 170\nwaist_girth = 70\nbust_girth = 90\n'
circle() { python3 -c "import math; print(', '.join('[%g, %g]' % ($1*math.cos(2*math.pi*k/8), $1*math.sin(2*math.pi*k/8)) for k in range(8)))"; }
C1=$(circle 1)
C2=$(circle 2)
fit_case "two different sections at one height" --sections dup.json "{\"units\": \"m\", \"sections\": [{\"height\": 0, \"points\": [$C1]}, {\"height\": 1, \"points\": [$C1]}, {\"height\": 1, \"points\": [$C2]}]}"
fit_case "a section of collinear points" --sections line.json "{\"units\": \"m\", \"sections\": [{\"height\": 0, \"points\": [$C1]}, {\"height\": 1, \"points\": [[0, 0], [1, 1], [2, 2]]}, {\"height\": 2, \"points\": [$C1]}]}"
fit_case "two sections only" --sections two.json "{\"units\": \"m\", \"sections\": [{\"height\": 0, \"points\": [$C1]}, {\"height\": 1, \"points\": [$C1]}]}"
fit_case "a section of two points" --sections pts.json "{\"units\": \"m\", \"sections\": [{\"height\": 0, \"points\": [$C1]}, {\"height\": 1, \"points\": [[0, 0], [1, 0]]}, {\"height\": 2, \"points\": [$C1]}]}"
new
case_ "$R" "fit: two sources (usage)" fit --sections a.json --measurements b.toml -o x.obj
if [[ -n $data ]]; then
    new
    case_ "$R" "fit: a scan band across the armpits" fit --from-mesh "$data/bodies/mean_female.obj" --up y --from 0.9 --to 1.35 -o x.obj
else
    missing+=("fit of a scan band across the armpits")
fi

# Other reader errors: patterns and garment flags (tests/garment.rs, bad_input.rs).
for fv in "--body-clearance=-0.001" "--cloth-friction=NaN" "--friction=-1" "--spacing=0"; do
    new
    case_ "$R" "garment: flag out of range ${fv%%=*}" garment p.json --body b.obj -o out "$fv"
done
new
cp "$fixtures/garments/tube_specification.json" .
case_ "$R" "garment: an explicit integrator" garment tube_specification.json --body no_such_body.obj -o out --integrator leapfrog
new
sed 's/"front"/"..\/front"/g' "$fixtures/garments/tube_specification.json" >tube_specification.json
case_ "Outputs stay where they belong" "garment: a panel named ../front with --panels" garment tube_specification.json --body no_such_body.obj -o out --panels
new
sed 's/\[0, 80, 30\]/[1e200, 80, 30]/' "$fixtures/garments/tube_specification.json" >tube_specification.json
case_ "$R" "garment: a panel translated by 1e200" garment tube_specification.json --body no_such_body.obj -o out
# tube_case KIND SED: the tube fixture edited by the sed script SED, refused by the reader.
tube_case() {
    new
    sed "$2" "$fixtures/garments/tube_specification.json" >tube_specification.json
    case_ "$R" "garment: $1" garment tube_specification.json --body no_such_body.obj -o out
}
tube_case "a panel name given twice" 's/"back":/"front":/'
tube_case "a stitch to edge -1" 's/"edge": 3}/"edge": -1}/'
tube_case "a panel with its vertices on a line" '0,/\[\[-30, 0\], \[30, 0\], \[30, 40\], \[-30, 40\]\]/s//[[0, 0], [10, 0], [20, 0], [30, 0]]/'
tube_case "edge loops twice round" 's/{"endpoints": \[3, 0\]}\],/{"endpoints": [3, 0]}, {"endpoints": [0, 1]}, {"endpoints": [1, 2]}, {"endpoints": [2, 3]}, {"endpoints": [3, 0]}],/'
tube_case "a panel name with a line break" 's/"back"/"back\\nv 1 2 3"/g'
tube_case "a vertex with three coordinates" 's/\[\[-30, 0\], \[30, 0\]/[[-30, 0, 0], [30, 0]/'
tube_case "an empty panel name" 's/"back"/""/g'
tube_case "a panel turned by 1e300 degrees" 's/"rotation": \[0, 180, 0\]/"rotation": [0, 1e300, 0]/'
tube_case "right_wrong given twice in a stitch" 's/{"panel": "back", "edge": 3}\]/{"panel": "back", "edge": 3}, "right_wrong", "right_wrong"]/'
tube_case "a key given twice in a stitch element" 's/{"panel": "back", "edge": 3}/{"panel": "back", "edge": 3, "edge": 2}/'
tube_case "a curvature with its type given twice" '0,/{"endpoints": \[0, 1\]}/s//{"endpoints": [0, 1], "curvature": {"type": "circle", "type": "cubic", "params": [[0.3, 0.1], [0.6, 0.1]]}}/'
tube_case "a panel 0.2 mm wide, too thin for the cloth at 1 cm" '0,/\[\[-30, 0\], \[30, 0\], \[30, 40\], \[-30, 40\]\]/s//[[-30, 0], [30, 0], [30, 0.02], [-30, 0.02]]/'
new
cp "$fixtures/garments/tube_specification.json" .
case_ "Outputs stay where they belong" "garment: --report over the pattern" garment tube_specification.json --body no_such_body.obj -o out --report tube_specification.json

# Other reader errors: batch plans (tests/batch.rs).
new
printf '[[garment]]\nname = "a"\nsceen = "x.toml"\n' >typo.toml
case_ "$R" "batch plan: misspelt key" batch plan typo.toml
new
printf 'fabrics = ["cotton", "velvet"]\n[[garment]]\nname = "square"\nscene = "%s"\n[[size]]\nname = "s"\nscale = 0\n[[size]]\nname = "s"\nscale = 1e300\n[fabric.rough]\nbase = "cotton"\nstrech = 3.0\n' "$fixtures/scenes/cotton_on_sphere.toml" >plan.toml
case_ "$R" "batch plan: bad values, every key at once" batch plan plan.toml
new
printf '[[garment]]\nname = "a"\nscene = "nowhere.toml"\n[[garment]]\nname = "b"\nscene = "%s"\n[[size]]\nname = "m"\n' "$fixtures/scenes/hanging_ribbon.toml" >plan.toml
case_ "$R" "batch plan: a missing scene, a scene without an object to scale" batch plan plan.toml

# ---------------------------------------------------------------------------------------------
# Bounded resources (tests/hostile_input.rs, hostile_memory.rs, batch.rs).
B="Bounded resources"
drape_case() { # drape_case CLASS KIND EDITS...: the sphere-drop scene edited, draped
    local class=$1 kind=$2
    shift 2
    new
    sphere_scene "$@"
    case_ "$class" "$kind" drape s.toml -o out
}
drape_case "$B" "collision grid of 4096^3 cells" 'cells = "auto"=>cells = [4096, 4096, 4096]'
grid=$n
drape_case "$B" "a step of 1e-300 s with a duration" 'dt = 1e-4=>dt = 1e-300' 'until_rest = 1e-5            # J of kinetic energy\nmax_steps = 40000=>duration = 1.0'
drape_case "$B" "a step of 1e-300 s with a step count" 'dt = 1e-4=>dt = 1e-300' 'until_rest = 1e-5            # J of kinetic energy\nmax_steps = 40000=>steps = 10'
drape_case "$B" "1e11 steps" 'max_steps = 40000=>max_steps = 100000000000'
drape_case "$B" "4e9 projective-dynamics iterations" 'integrator = "leapfrog"=>integrator = "projective-dynamics"\niterations = 4000000000'
drape_case "$B" "Newton and CG iteration counts" 'integrator = "leapfrog"=>integrator = "implicit-euler"\nnewton_iterations = 101\ncg_max_iterations = 4294967295'
drape_case "$B" "a frame every step over 40,000 steps" 'cells = "auto"=>cells = "auto"\n[output]\nframes = 1'
drape_case "$B" "2.6 million particles (spacing 0.5 mm)" 'spacing = 0.02=>spacing = 0.0005'
particles=$n
new
printf '[[garment]]\nname = "a"\nscene = "%s"\n[solver]\niterations = 1001\nnewton_iterations = 4000000000\nanderson = 21\nsteps = 100000001\n[garment_solver]\nsettle_max = 1e300\n' "$fixtures/scenes/hanging_ribbon.toml" >plan.toml
case_ "$B" "batch plan: solver counts beyond the scene limits" batch plan plan.toml
new
python3 -c '
print("fabrics = [\"cotton\", \"silk\"]")
print("[[garment]]\nname = \"square\"\nscene = \"%s\"" % "'"$fixtures/scenes/cotton_on_sphere.toml"'")
for i in range(100000):
    print("[[size]]\nname = \"s%d\"" % i)' >plan.toml
case_ "$B" "batch plan: an axes product of 200,000 jobs" batch plan plan.toml
new
python3 -c '
print("[[garment]]\nname = \"square\"\nscene = \"%s\"" % "'"$fixtures/scenes/cotton_on_sphere.toml"'")
for i in range(100000):
    print("[[size]]\nname = \"s%d\"" % i)
for i in range(100001):
    print("[[job]]\ngarment = \"square\"\nsize = \"s%d\"" % (i % 100000))' >plan.toml
case_ "$B" "batch plan: a [[job]] list of 100,001 jobs" batch plan plan.toml
for fv in "--sew-max 1e300" "--settle-max 3601"; do
    new
    # shellcheck disable=SC2086
    case_ "$B" "garment: stage time ${fv% *}" garment p.json --body b.obj -o out $fv
done
for args in "speed --runs 1001" "speed --side 1001" "speed --iterations 1001" "speed --low-rank-max 4097" "inside b.obj --points 10000001" "drape --steps 100000001" "speed --duration 1e300"; do
    new
    # shellcheck disable=SC2086
    case_ "$B" "bench ${args% *} beyond its limit" bench $args
done
for fl in "--nodes 1000000000" "--around 100000 --along 100000" "--levels 1000000000"; do
    new
    # shellcheck disable=SC2086
    case_ "$B" "fit: ${fl}" fit --measurements "$fixtures/measurements_size38.toml" -o x.obj $fl
done
new
{ printf 'v 0 0 0\nv 1 0 0\n# '; head -c $((2 << 20)) /dev/zero | tr '\0' x; printf '\nv 0 1 0\nf 1 2 3\n'; } >long.obj
case_ "$B" "an OBJ comment line of 2 MiB" convert long.obj -o o.obj
new
python3 -c '
import sys
s = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3" + (" \\\n" + " " * 1000) * 2000 + "\n"
sys.stdout.write(s)' >continued.obj
case_ "$B" "an OBJ face continued over 2,000 lines (2 MB)" convert continued.obj -o o.obj
new
{ printf '0 0 0\n'; head -c $((3 << 19)) /dev/zero | tr '\0' 1; printf ' 0 0\n0 1 0\n'; } >long.txt
case_ "$B" "a vertex-triples line of 1.5 MiB of digits" convert long.txt -o o.obj
new
{ printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\n'; head -c 30000000 /dev/zero | tr '\0' '\n'; printf 'f 1 2 3\nv 1 2 x\n'; } >blank.obj
case_ "$B" "30 million blank lines, then a bad number (memory: see below)" convert blank.obj -o o.obj
rm -f blank.obj
new
cp "$fixtures/scenes/sphere_r0.3.obj" .
python3 -c '
import math
n = 100000
pts = ", ".join("[%.9f, %.9f]" % (0.4 * math.cos(2 * math.pi * k / n) * (1 + 0.02 * (k % 2)), 0.4 * math.sin(2 * math.pi * k / n) * (1 + 0.02 * (k % 2))) for k in range(n))
print("units = \"m\"\n[solver]\ndt = 1e-3\nsteps = 2\n[[object]]\nmesh = \"sphere_r0.3.obj\"\n[[piece]]\nname = \"star\"\noutline = [%s]\nspacing = 0.02\nposition = [0.0, 0.0, 0.4]\nfabric = \"cotton\"" % pts)' >s.toml
star=$n
check='test -s out/star.obj && echo "the piece was written"'
case_ "$B" "a piece outline of 100,000 corners (a star, two steps)" drape s.toml -o out

# ---------------------------------------------------------------------------------------------
# Outputs stay where they belong, and nothing is lost (tests/hostile_outputs.rs, interrupt.rs,
# resume.rs, bad_input.rs, hostile_input.rs).
O="Outputs stay where they belong"
drape_case "$O" "piece named ../up" "$FIVE" 'name = "square"=>name = "../up"'
new
sphere_scene "$FIVE" "name = \"square\"=>name = \"$d/escaped\""
case_ "$O" "piece named by an absolute path" drape s.toml -o out
drape_case "$O" "piece named sub/x" "$FIVE" 'name = "square"=>name = "sub/x"'
drape_case "$O" "piece with an empty name" "$FIVE" 'name = "square"=>name = ""'
new
printf '0 0 0\n1 0 0\n0 1 0\n' >in.txt
case_ "$O" "output path under a regular file" convert in.txt -o in.txt/out.ply
new
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n' >in.obj
check='cmp -s in.obj <(printf "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n") && echo "input unchanged"'
case_ "$O" "output over the input (spelt ./in.obj)" convert in.obj -o ./in.obj
new
printf '0 0 0\n1 0 0\n0 1 0\n' >in.txt
check='test -e o.ply && echo "o.ply written" || echo "no o.ply"'
case_ "$O" "report path equal to the output" convert in.txt -o o.ply --report o.ply
TWO='[[piece]]\nname = "b"\noutline = [[-0.1, -0.1], [0.1, -0.1], [0.1, 0.1], [-0.1, 0.1]]\nspacing = 0.05\nposition = [0.0, 0.0, 0.6]\nfabric = "soft_cotton"\n\n[output]\nply = true\nframes = 1\n\n# Cotton'
new
sphere_scene "$FIVE" 'name = "square"=>name = "a"' "# Cotton=>$TWO"
"$exe" drape s.toml -o out >/dev/null 2>&1
(cd out && find . -type f -exec sha256sum {} + | sort) >before.sums
sphere_scene "$FIVE" 'name = "square"=>name = "a"' "# Cotton=>$TWO" '[output]=>[[piece]]\nname = "c"\noutline = [[-0.1, -0.1], [0.1, -0.1], [0.1, 0.1], [-0.1, 0.1]]\nspacing = 0.05\nposition = [0.0, 0.0, 0.9]\nfabric = "soft_cotton"\n\n[output]'
mkdir out/c.obj
check='rmdir out/c.obj; (cd out && find . -type f -exec sha256sum {} + | sort) | cmp -s - before.sums && echo "the earlier run'"'"'s files byte-identical" || echo "EARLIER FILES CHANGED"'
case_ "$O" "a rerun that fails writing one file (c.obj is a folder)" drape s.toml -o out
sphere_scene "$FIVE" 'name = "square"=>name = "a"' "# Cotton=>$TWO" 'dt = 1e-4=>dt = 0.05' 'steps = 5=>steps = 2000'
check='(cd out && find . -type f -exec sha256sum {} + | sort) | cmp -s - before.sums && echo "the earlier run'"'"'s files byte-identical, no temporary file" || echo "EARLIER FILES CHANGED"'
case_ "$O" "a rerun that goes unstable after writing frames" drape s.toml -o out
float_ply() { printf 'ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar float vertex_indices\nend_header\n%s 0 0\n1 0 0\n0 1 0\n%s\n' "$1" "$2"; }
new; float_ply 0 "3 0 1.7 2" >fi.ply
case_ "$O" "PLY face index 1.7" convert fi.ply -o out.ply
new; float_ply 0 "3 0 1 nan" >fn.ply
case_ "$O" "PLY face index NaN" convert fn.ply -o out.ply
new; float_ply 1e39 "3 0 1 2" >big.ply
case_ "$O" "PLY float coordinate 1e39 (beyond f32)" convert big.ply -o out.ply
# tetra S: a regular tetrahedron at scale S, as t.obj in a fresh case folder.
tetra() {
    new
    python3 -c "
s = $1
for q in [(1, 1, 1), (1, -1, -1), (-1, 1, -1), (-1, -1, 1)]:
    print('v %r %r %r' % (q[0] * s, q[1] * s, q[2] * s))
print('f 1 2 3\nf 1 3 4\nf 1 4 2\nf 2 4 3')" >t.obj
}
for s in 1e100 1e-100 1e300; do
    tetra "$s"
    check='test -e o.obj && echo "$(grep -c "^f " o.obj) faces written" || echo "nothing written"'
    case_ "$O" "a regular tetrahedron at scale $s" convert t.obj -o o.obj
done
for s in 1e-40 1e-300; do
    tetra "$s"
    case_ "$O" "a regular tetrahedron at scale $s to binary STL (too small for 32-bit floats)" convert t.obj -o o.stl
done
drape_case "$O" "cloth placed at 1e308 m" 'position = [0.0, 0.0, 0.33]=>position = [0.0, 0.0, 1e308]'

# Interrupts and resumes (tests/interrupt.rs, resume.rs): cotton on the sphere, 300 steps, a
# frame every 10, stopped when the first frame is being written.
drop_scene() { # drop_scene DIR DROP: the interrupt tests' scene as DIR/drop.toml
    mkdir -p "$1"
    cp "$fixtures/scenes/sphere_r0.3.obj" "$1"
    python3 - "$fixtures/scenes/cotton_on_sphere.toml" "$2" >"$1/drop.toml" <<'EOF'
import sys
s = open(sys.argv[1]).read()
s = s.replace("until_rest = 1e-6", "steps = 300").replace("max_steps = 1000", "")
s = s.replace("position = [0.0, 0.0, 0.33]", "position = [0.0, 0.0, %s]" % sys.argv[2])
print(s + "\n[output]\nframes = 10")
EOF
}
new
drop_scene a 0.33
"$exe" drape a/drop.toml -o ref --glb >/dev/null 2>&1
interrupt_case() { # interrupt_case SIGNAL
    local sig=$1 code=0 t0
    rm -rf out
    "$exe" drape a/drop.toml -o out --glb >/dev/null 2>"$d/.err" &
    local pid=$!
    t0=$SECONDS
    until [[ -d out/frames && -n $(ls -A out/frames 2>/dev/null) ]]; do
        ((SECONDS - t0 < 600)) || break
        sleep 0.002
    done
    kill -s "$sig" "$pid"
    wait "$pid" || code=$?
    local temps frames
    temps=$(find out -name '*.tmp' | wc -l)
    frames=$(find out/frames -type f | wc -l)
    "$exe" drape a/drop.toml -o out --glb --resume >/dev/null 2>"$d/.err2" || true
    local same="no"
    if diff -rq ref out >/dev/null 2>&1; then same="yes"; fi
    row=$((row + 1))
    printf '| %d | %s | %s | `%s` | %d | %s |\n' "$row" "$O" \
        "$(clean "SIG$sig during the run; checked: temporary files: $temps, finished frames kept: $frames; --resume gives the uninterrupted run's files byte for byte: $same")" \
        "drapekit drape a/drop.toml -o out --glb; kill -$sig after the first frame; then --resume" \
        "$code" "$(clean "$(first_line "$d/.err")")" >>"$rows"
}
interrupt_case INT
interrupt_case TERM
# A checkpoint to refuse: interrupted again, then resumed against other things.
rm -rf out
"$exe" drape a/drop.toml -o out --glb >/dev/null 2>&1 &
pid=$!
until [[ -d out/frames && -n $(ls -A out/frames 2>/dev/null) ]]; do sleep 0.002; done
kill -INT $pid
wait $pid || true
cp out/drop.checkpoint good.checkpoint
drop_scene b 0.40
case_ "$O" "resume: another scene's checkpoint (same name)" drape b/drop.toml -o out --glb --resume
case_ "$O" "resume: other options (no --glb)" drape a/drop.toml -o out --resume
case_ "$O" "resume: no checkpoint" drape a/drop.toml -o elsewhere --resume
ck_case() { # ck_case KIND PYTHON-EDIT-OF-b
    python3 -c "
b = bytearray(open('good.checkpoint', 'rb').read())
$2
open('out/drop.checkpoint', 'wb').write(bytes(b))"
    case_ "$O" "resume: $1" drape a/drop.toml -o out --glb --resume
}
ck_case "a checkpoint with one bit flipped" 'b[len(b) // 2] ^= 4'
ck_case "a checkpoint cut short" 'b = b[:-1]'
ck_case "a text file as the checkpoint" 'b = bytearray(b"# a scene file\n[solver]\n")'
ck_case "a checkpoint of another version" 'b[16] = 2'
new
drop_scene . 0.33
sed -i 's/steps = 300/steps = 3/' drop.toml
mkdir -p out/frames
prefix=.drapekit-tmp-
for f in "${prefix}4194305-square.obj.Ab12Cd.tmp" "frames/${prefix}4194305-square_0000010.obj.Ef34Gh.tmp" ".square.obj.Ab12Cd.tmp" notes.txt; do
    echo partial >"out/$f"
done
check='echo "left: $(cd out && find . -name "*.tmp" -o -name notes.txt | sort | tr "\n" " ")"'
case_ "$O" "stale temporary files of a killed run (and two files not ours)" drape drop.toml -o out

# ---------------------------------------------------------------------------------------------
# Messages that help (tests/hostile_outputs.rs, hostile_input.rs, drape.rs, fit.rs).
M="Messages that help"
drape_case "$M" "huge and tiny keys (four problems)" "$FIVE" 'friction = 0.3=>friction = 1e300' 'dt = 1e-4=>dt = -1e300' 'spacing = 0.02=>spacing = -1e-300' 'thickness = 0.002=>thickness = 0.002\ndensity = -1e300'
drape_case "$M" "a duration of 1e300 s" "$FIVE" 'steps = 5=>duration = 1e300'
drape_case "$M" "a fabric too stiff and light for any stable step" "$FIVE" 'dt = 1e-4\n=>' 'stretch = 1000.0=>stretch = 1e300\ndensity = 1e-300'
new
cp "$fixtures/scenes/hanging_ribbon.toml" .
python3 - <<'EOF'
s = open("hanging_ribbon.toml").read()
import re
s = s.replace("dt = 2e-4", "dt = 0.02")
s = re.sub(r"until_rest = [^\n]*\nmax_steps = [^\n]*", "steps = 2000", s)
open("s.toml", "w").write(s + "\n[output]\nframes = 1\nply = true\n")
EOF
check='test -e out && echo "out written" || echo "nothing written"'
case_ "$M" "an explicit step 100 times too large" drape s.toml -o out
new
printf 'units = "cm"\nstature = 166\nwaist_girth = 80\nhip_girth = -1e300\n' >m.toml
case_ "$M" "a girth of -1e300" fit --measurements m.toml -o x.obj
if [[ -n $data ]]; then
    new
    case_ "$M" "fit of a Y-up body without --up y" fit --from-mesh "$data/bodies/mean_all.obj" -o form.obj
else
    missing+=("fit of a Y-up body without --up y")
fi
drape_case "$M" "an object in centimetres in a metre scene (cloth inside it)" "$FIVE" 'friction = 0.3=>friction = 0.3\nscale = 100.0'
drape_case "$M" "cloth placed through the sphere's centre" "$FIVE" 'position = [0.0, 0.0, 0.33]=>position = [0.0, 0.0, 0.0]'
new
printf 'v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nf 1 3 2\nf 1 4 3\nf 1 2 6\nf 1 6 5\nf 2 3 7\nf 2 7 6\nf 3 4 8\nf 3 8 7\nf 4 1 5\nf 4 5 8\n' >sheet.obj
sphere_scene "$FIVE" 'mesh = "sphere_r0.3.obj"=>mesh = "sheet.obj"'
show="particles inside objects"
case_ "$M" "an open collider (a box without its lid)" drape s.toml -o out
new
cp "$fixtures/scenes/sphere_r0.3.obj" .
case_ "$M" "--ascii with an OBJ output" convert sphere_r0.3.obj -o x.obj --ascii
new
cp "$fixtures/scenes/sphere_r0.3.obj" .
case_ "$M" "--units and --up without --to-units, --to-up" convert sphere_r0.3.obj -o y.obj --units mm --up y

# ---------------------------------------------------------------------------------------------
# render, inspect and fit: hostile flags, frames folders and outputs (tests/render.rs, fit.rs,
# roundtrip.rs).
O="Outputs stay where they belong"
TRI='v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n'
CUBE='v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\nf 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 2 3 7\nf 2 7 6\nf 3 4 8\nf 3 8 7\nf 4 1 5\nf 4 5 8\n'
new
case_ "$B" "render: --width 8193, refused before the (missing) mesh is read" render nope.obj -o o.png --width 8193
new
mkdir -p frames
printf "$TRI" >frames/sq_0000010.obj
printf "$TRI" >frames/sq_0000020.obj
printf "$TRI" >frames/cape_0000020.obj
printf "$CUBE" >frames/sq_0000030.obj
check='test -e o.png && echo "o.png written" || echo "no o.png"'
case_ "$R" "render: a frames folder of two runs (pieces and meshes differ between steps)" render frames -o o.png
new
mkdir -p frames
printf "$TRI" >frames/a_01.obj
printf "$TRI" >frames/a_1.obj
case_ "$R" "render: a frames folder with one piece twice at a step" render frames -o o.png
new
mkdir -p frames
case_ "$R" "render: a frames folder with no frame files" render frames -o o.png
new
printf 'v 0 0 0\nv 1e90 0 0\nv 0 1 0\nvt 0 0\nvt 1e-250 0\nvt 0 1\nf 1/1 2/2 3/3\n' >far.obj
case_ "$R" "render: a strain beyond the range of numbers (1e90 over 1e-250)" render far.obj -o o.png --color strain
new
mkdir o.png
case_ "$O" "render: the picture is an existing folder (refused before reading)" render nope.obj -o o.png
new
case_ "$O" "render: the picture in a folder that does not exist" render nope.obj -o no/such/o.png
new
printf "$TRI" >in.png
check='cmp -s in.png <(printf "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n") && echo "input unchanged"'
case_ "$O" "render: the picture is the input (an OBJ named .png, read with --from obj)" render in.png -o in.png --from obj
new
printf "$TRI" >tri.obj
case_ "$M" "render: --fps 0.01 (a delay beyond APNG's 65.535 s)" render tri.obj -o o.png --fps 0.01
new
printf "$TRI" >tri.obj
case_ "$M" "render: --mesh-colors with more colours than meshes" render tri.obj -o o.png --mesh-colors '#ff0000,#00ff00'
new
printf "$TRI" >tri.obj
case_ "$M" "render: --to with --color strain (ignored before)" render tri.obj -o o.png --color strain --to tri.obj
new
printf "$TRI" >tri.obj
case_ "$M" "render: a colour range whose span is beyond the numbers" render tri.obj -o o.png --color distance --to tri.obj --range=-1e308:1e308
new
mkdir r.json
case_ "$O" "inspect: --report an existing folder (refused before reading)" inspect nope.obj --report r.json
new
printf 'v 0 0 0\nv 0.001 0 0\nv 0 0.001 0\nv 0 0 0.001\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n' >tet.obj
show="closed volumes"
case_ "$M" "inspect: a 1 mm tetrahedron in metres (its volume, once 0.000000)" inspect tet.obj
new
check='test -e form.obj && echo "form.obj written" || echo "no form.obj"'
case_ "$O" "fit: --report equal to the form" fit --measurements "$fixtures/measurements_size38.toml" -o form.obj --report form.obj
new
check='test -e form.obj -o -e form.png && echo "AN OUTPUT WRITTEN" || echo "nothing written"'
case_ "$O" "fit: --report equal to the --preview picture" fit --measurements "$fixtures/measurements_size38.toml" -o form.obj --preview --report form.png
new
case_ "$M" "fit: every count out of range at once" fit --measurements "$fixtures/measurements_size38.toml" -o form.obj --nodes 0 --around 2 --along 1 --stride 0
new
case_ "$M" "fit: --levels 0 with measurements" fit --measurements "$fixtures/measurements_size38.toml" -o form.obj --levels 0
new
case_ "$M" "fit: an output extension fit does not write (the hint names --format)" fit --measurements "$fixtures/measurements_size38.toml" -o form.png
new
case_ "$M" "fit: --units with a measurement set (which gives its own)" fit --measurements "$fixtures/measurements_size38.toml" -o form.obj --units mm
new
case_ "$R" "fit: --units against a sections JSON that states others" fit --sections "$fixtures/torso_sections.json" -o form.obj --units mm
new
python3 -c "print('height,x,y'); [print(f'{k},1,0\\n{k},0,1\\n{k},-1,0') for k in range(10001)]" >many.csv
case_ "$B" "fit: a sections file of 10,001 sections (the fit's time grows as their square)" fit --sections many.csv -o form.obj
new
printf 'units = "cm"\nstature = 170\nwaist_girth = 70\nbust_girth = 1e-20\n' >thin.toml
case_ "$M" "fit: a bust of 1e-20 cm (once 'section 26 is degenerate')" fit --measurements thin.toml -o form.obj
fit_case "a GarmentCode body YAML with a key given twice" --measurements dup.yaml 'body:\n  height: 170\n  waist: 70\n  bust: 90\n  height: 180\n'
fit_case "a FreeSewing JSON with a key given twice" --measurements dup.json '{"measurements": {"waist": 700, "chest": 900,\n "waist": 800}}\n'
new
python3 -c "print('a0: &a0 [x, x, x, x, x, x, x, x, x, x]'); [print(f'a{i}: &a{i} [' + ', '.join([f'*a{i-1}'] * 10) + ']') for i in range(1, 10)]; print('body: {height: 170, waist: 70, bust: 90}')" >bomb.yaml
case_ "$B" "fit: a GarmentCode YAML whose aliases expand 10^10 times" fit --measurements bomb.yaml -o form.obj
fit_case "a scan whose every face is degenerate" --from-mesh line.obj 'v 0 0 0\nv 1 1 1\nv 2 2 2\nf 1 2 3\n'

# ---------------------------------------------------------------------------------------------
# Preparation never breaks a good mesh; measurements brought in (real data).
if [[ -n $data ]]; then
    for b in mean_all mean_female mean_male makehuman_hm08_body_only_m; do
        new
        show="shell state"
        case_ "Preparation" "the real body $b.obj through the default weld (shell state after)" convert "$data/bodies/$b.obj" -o x.ply
    done
    new
    show="stature"
    case_ "Measurements" "a FreeSewing JSON set (mm) read as it is" fit --measurements "$data/measurements/with_breasts_base_set_mm.json" -o x.obj
    new
    show="not used"
    case_ "Measurements" "a GarmentCode body YAML (cm) read as it is" fit --measurements "$data/bodies/mean_all.yaml" -o x.obj
else
    missing+=("the real bodies through the weld" "FreeSewing and GarmentCode measurement sets")
fi
new
printf '{"name": "someone", "sizes": {"waist": 700}}\n' >m.json
case_ "Measurements" "a JSON file that is no FreeSewing set" fit --measurements m.json -o x.obj
new
printf '{"measurements": {"waist": "wide", "chest": 900}}\n' >fs.json
case_ "Measurements" "a FreeSewing set with a word for a number" fit --measurements fs.json -o x.obj

# ---------------------------------------------------------------------------------------------
cd "$here"
cpu=$(sed -n 's/^model name\s*: //p' /proc/cpuinfo | head -1)
mem=$(awk '/MemTotal/ {printf "%.0f GiB", $2 / 1048576}' /proc/meminfo)
echo "# Bad input: the catalogue"
echo
echo "Every kind of bad input, fault and trap the tests cover (issue 9), made afresh and given to"
echo "the release binary. Regenerate with \`tools/bad_input_catalogue.sh > docs/bad-input.md\`"
echo "(\`--memory\` adds the peak-memory table)."
echo
echo "- $(date -u '+%Y-%m-%d %H:%M UTC'), drapekit $(git -C "$here" rev-parse --short HEAD)"
echo "- $(uname -sr), $(nproc) cores ($cpu), $mem"
echo "- **$row kinds**: exit status 1 is a refused input, 2 a usage error, 130/143 an interrupted"
echo "  run (SIGINT/SIGTERM), 0 a hostile input that must give an answer (what was checked follows"
echo "  the kind)."
echo "- by class: $(cut -d'|' -f3 "$rows" | sed 's/^ *//; s/ *$//' | sort | uniq -c | sort -rn |
    awk '{ n = $1; $1 = ""; printf "%s%d%s", (NR > 1 ? ", " : ""), n, $0 }')"
echo "- interrupts: SIGINT and SIGTERM when the first frame is being written, then \`--resume\`"
echo "  (rows of class *Outputs stay where they belong* that start with SIG); refused resumes follow."
((${#missing[@]})) && echo "- left out (no ../shared/realdata): ${missing[*]}"
echo
echo "| # | class | kind | command | exit | first line of stderr |"
echo "|---|---|---|---|---|---|"
cat "$rows"
$memory || exit 0

# ---------------------------------------------------------------------------------------------
# Peak memory (--memory): /usr/bin/time -v's maximum resident set size, and the wall time.
mrows=$work/memory.md
: >"$mrows"
# mem INPUT SIZE ARGS...: drapekit ARGS run under /usr/bin/time in the current folder; a row.
mem() {
    local input=$1 size=$2
    shift 2
    /usr/bin/time -v "$exe" "$@" >/dev/null 2>"$work/time" </dev/null || true
    local kb wall code cmd="drapekit" a
    kb=$(sed -n 's/.*Maximum resident set size (kbytes): //p' "$work/time")
    wall=$(sed -n 's/.*Elapsed (wall clock) time (h:mm:ss or m:ss): //p' "$work/time")
    code=$(sed -n 's/.*Exit status: //p' "$work/time")
    for a in "$@"; do cmd="$cmd $(printf '%q' "$a")"; done
    printf '| %s | %s | %s | %s | %s | `%s` |\n' "$input" "$size" \
        "$(awk -v k="$kb" 'BEGIN { printf "%.1f MB", k / 1024 }')" "$wall" "$code" \
        "$(clean "$cmd")" >>"$mrows"
}
# counts FILE: its size (a .gltf's with its buffer files), vertices and faces as read.
counts() {
    local v f bytes u
    read -r v f < <("$exe" inspect "$1" --json 2>/dev/null | jq -r '"\(.vertices) \(.faces)"') || true
    bytes=$(stat -c %s "$1")
    if [[ $1 == *.gltf ]]; then
        for u in $(jq -r '.buffers[].uri | select(startswith("data:") | not)' "$1"); do
            bytes=$((bytes + $(stat -c %s "$(dirname "$1")/$u")))
        done
    fi
    printf '%s, %s vertices, %s faces' "$(numfmt --to=si --suffix=B "$bytes")" "${v:-?}" "${f:-?}"
}
new
{ printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\n'; head -c 1000000000 /dev/zero | tr '\0' '\n'; printf 'f 1 2 3\n'; } >/tmp/drapekit-blank.obj
mem "1 GB of blank lines as OBJ (one triangle)" "1.0 GB, 10^9 lines" convert /tmp/drapekit-blank.obj -o o.obj
rm -f /tmp/drapekit-blank.obj
{ printf '0 0 0\n1 0 0\n0 1 0\n'; head -c 1000000000 /dev/zero | tr '\0' '\n'; } >/tmp/drapekit-blank.txt
mem "1 GB of blank lines as vertex triples (one triangle)" "1.0 GB, 10^9 lines" convert /tmp/drapekit-blank.txt -o o.obj
rm -f /tmp/drapekit-blank.txt
if [[ -n $data ]]; then
    for f in bodies/mean_male.obj bodies/mean_all.obj meshes/trimesh/cycloidal.ply meshes/assimp/PLY/Wuson.ply meshes/trimesh/capsule.obj seats/sofa_03_1k.gltf; do
        sz=$(counts "$data/$f")
        mem "realdata/$f: convert" "$sz" convert "$data/$f" -o "x.${f##*.}"
        mem "realdata/$f: inspect" "$sz" inspect "$data/$f"
    done
fi
mem "a 100,000-corner outline (drape, two steps)" "$(numfmt --to=si --suffix=B "$(stat -c %s "$work/case$star/s.toml")") scene, 101,201 particles" drape "$work/case$star/s.toml" -o star
sed 's/spacing = 0.05/spacing = 0.0025/; s/steps = 10/steps = 2/; s/dt = 1e-4/dt = 1e-3/' "$fixtures/bad_scene_base.toml" >"$work/case$star/square.toml"
mem "for comparison: a plain square of as many particles (drape, two steps)" "spacing 2.5 mm, 103,041 particles" drape "$work/case$star/square.toml" -o square
python3 -c '
print("[[garment]]\nname = \"square\"\nscene = \"%s\"" % "'"$fixtures/scenes/cotton_on_sphere.toml"'")
for i in range(100000):
    print("[[size]]\nname = \"s%d\"" % i)
for i in range(100000):
    print("[[job]]\ngarment = \"square\"\nsize = \"s%d\"" % i)' >"$work/plan100k.toml"
mem "batch plan of 100,000 listed jobs (the limit)" "$(numfmt --to=si --suffix=B "$(stat -c %s "$work/plan100k.toml")") plan" batch plan "$work/plan100k.toml"
mem "collision grid of 4096^3 cells (refused)" "68,719,476,736 cells asked" drape "$work/case$grid/s.toml" -o g
mem "2.6 million particles (refused)" "spacing 0.5 mm" drape "$work/case$particles/s.toml" -o p
mem "fit --nodes 10^9 (refused)" "10^9 nodes asked" fit --measurements "$fixtures/measurements_size38.toml" -o x.obj --nodes 1000000000
mem "fit --around 10^5 --along 10^5 (refused)" "10^10 vertices asked" fit --measurements "$fixtures/measurements_size38.toml" -o x.obj --around 100000 --along 100000
if [[ -n $data ]]; then
    mem "fit of the real body mean_all.obj" "$(counts "$data/bodies/mean_all.obj")" fit --from-mesh "$data/bodies/mean_all.obj" --up y -o form.obj
    mem "garment: dress_pencil on mean_all.obj, 0.2 s + 0.2 s" "$(numfmt --to=si --suffix=B "$(stat -c %s "$data/patterns/dress_pencil_specification.json")") pattern" \
        garment "$data/patterns/dress_pencil_specification.json" --body "$data/bodies/mean_all.obj" -o g --sew-max 0.2 --settle-max 0.2
fi
# An animation: 300 frames of the sphere drop, drawn at 1600 x 1200 px (each picture encoded
# as it is drawn; holding them all took 1.8 GB).
new
sphere_scene 'max_steps = 40000=>max_steps = 3000'
printf '\n[output]\nframes = 10\n' >>s.toml
"$exe" drape s.toml -o out >/dev/null 2>&1 || true
mem "render: 300 frames at 1600 x 1200 px" "$(find out/frames -name '*.obj' | wc -l) frames of 1681 vertices" \
    render out/frames out/sphere_r0.3.obj -o anim.png --width 1600 --height 1200
echo
echo "## Peak memory"
echo
echo "The maximum resident set size (\`/usr/bin/time -v\`) and the wall time of the release binary on"
echo "the largest inputs, the refused huge requests, a fit and a garment on the real body"
echo "(\`tools/bad_input_catalogue.sh --memory\`; the machine above, shared with other work)."
echo
echo "| input | size | peak RSS | wall | exit | command |"
echo "|---|---|---|---|---|---|"
cat "$mrows"
