//! Reading glTF 2.0 (`.gltf` JSON with external or `data:` buffers, `.glb`) into one [`TriMesh`].
//!
//! Every triangle primitive of every mesh a node of the scene places is merged, its positions
//! carried through the node's world matrix (the product of the local matrices from the root
//! down; a local matrix is `matrix`, or `T * R * S` from translation, rotation and scale). A
//! world matrix of negative determinant mirrors, and its triangles are turned back (`a, c, b`)
//! so that they keep their outward side, as the specification says; a mesh under a singular `W`
//! (a node scaled to zero: hidden, as the frames of drapekit's animations are) is left out.
//! Every size the file gives is checked against the bytes that are there before anything is
//! allocated.

use super::glb;
use crate::io::error::{malformed, IoError, Location, ProblemKind};
use crate::io::{check_vertex_count, ReadInfo, ReadOutput};
use crate::math::Point3;
use crate::mesh::polygon::PolygonStats;
use crate::mesh::TriMesh;
use gltf_json::accessor::{ComponentType, Type};
use gltf_json::mesh::{Mode, Semantic};
use gltf_json::validation::Checked;
use gltf_json::Root;
use nalgebra::{Matrix4, Quaternion, UnitQuaternion, Vector3};
use std::borrow::Cow;
use std::io::Read;
use std::path::Path;

/// The most vertices that instancing (one mesh placed by several nodes) may make, unless the file
/// itself stores more: 2^25, 800 MB of positions and faces.
pub const MAX_PLACED_VERTICES: u64 = 1 << 25;

/// One triangle primitive, decoded.
#[derive(Debug, Default)]
struct Primitive {
    positions: Vec<[f32; 3]>,
    triangles: Vec<[u32; 3]>,
}

/// A parsed document and its loaded buffers.
struct Doc<'a> {
    path: &'a Path,
    format: &'static str,
    root: Root,
    buffers: Vec<Cow<'a, [u8]>>,
}

/// Reads a `.gltf` or `.glb` file's bytes (`path` names it and locates external buffers).
pub fn read(path: &Path, bytes: &[u8]) -> Result<ReadOutput, IoError> {
    let doc = Doc::parse(path, bytes)?;
    let mut warnings = doc.notes();
    let placed = doc.instances(&mut warnings)?;
    let mut decoded: Vec<Option<Vec<Primitive>>> = doc.root.meshes.iter().map(|_| None).collect();
    for (m, _, _) in &placed {
        if decoded[*m].is_none() {
            decoded[*m] = Some(doc.mesh(*m)?);
        }
    }
    let count = |m: usize| -> u64 {
        let prims = decoded[m].as_deref().unwrap_or_default();
        prims.iter().map(|p| p.positions.len() as u64).sum()
    };
    let total: u64 = placed.iter().map(|(m, ..)| count(*m)).sum();
    let stored: u64 = (0..decoded.len()).map(count).sum();
    let limit = MAX_PLACED_VERTICES.max(stored);
    if total > limit {
        let kind = ProblemKind::GltfTooLarge {
            vertices: total,
            limit,
        };
        return Err(malformed(
            path,
            doc.format,
            Location::Key("nodes".into()),
            kind,
        ));
    }
    check_vertex_count(path, total as usize)?;
    let mut mesh = TriMesh::default();
    for (m, world, _) in &placed {
        for p in decoded[*m].as_deref().unwrap_or_default() {
            place(&mut mesh, p, world);
        }
    }
    let info = ReadInfo {
        format: if doc.format == "glTF" { "gltf" } else { "glb" }.into(),
        vertices_in_file: mesh.positions.len(),
        polygons: PolygonStats {
            polygons: mesh.faces.len(),
            triangles: mesh.faces.len(),
            ..PolygonStats::default()
        },
        warnings,
        ..ReadInfo::default()
    };
    Ok(ReadOutput {
        mesh,
        info,
        texcoords: None,
    })
}

/// Appends primitive `p` carried by `world` to `mesh`.
fn place(mesh: &mut TriMesh, p: &Primitive, world: &Matrix4<f64>) {
    let base = mesh.positions.len() as u32;
    let identity = *world == Matrix4::identity();
    mesh.positions.extend(p.positions.iter().map(|q| {
        let q = Point3::new(f64::from(q[0]), f64::from(q[1]), f64::from(q[2]));
        if identity {
            q
        } else {
            world.transform_point(&q)
        }
    }));
    let mirror = world.fixed_view::<3, 3>(0, 0).determinant() < 0.0;
    mesh.faces.extend(p.triangles.iter().map(|t| {
        let [a, b, c] = t.map(|v| v + base);
        if mirror {
            [a, c, b]
        } else {
            [a, b, c]
        }
    }));
}

/// The local matrix of a node: `matrix` (column-major), or `T * R * S`.
fn local_matrix(node: &gltf_json::Node) -> Matrix4<f64> {
    if let Some(m) = node.matrix {
        return Matrix4::from_column_slice(&m.map(f64::from));
    }
    let t = node.translation.unwrap_or([0.0; 3]).map(f64::from);
    let s = node.scale.unwrap_or([1.0; 3]).map(f64::from);
    let [x, y, z, w] = node
        .rotation
        .map_or([0.0, 0.0, 0.0, 1.0], |r| r.0.map(f64::from));
    let r = UnitQuaternion::from_quaternion(Quaternion::new(w, x, y, z));
    Matrix4::new_translation(&Vector3::from(t))
        * r.to_homogeneous()
        * Matrix4::new_nonuniform_scaling(&Vector3::from(s))
}

/// A mesh placed by the scene: the mesh, its world matrix, the key of the node placing it.
type Instance = (usize, Matrix4<f64>, String);

impl<'a> Doc<'a> {
    fn err(&self, key: String, kind: ProblemKind) -> IoError {
        malformed(self.path, self.format, Location::Key(key), kind)
    }

    /// The JSON (from the GLB container or the whole file), parsed, and the buffers loaded.
    fn parse(path: &'a Path, bytes: &'a [u8]) -> Result<Doc<'a>, IoError> {
        let text = bytes.strip_prefix(&[0xEF, 0xBB, 0xBF]).unwrap_or(bytes);
        let is_json = text.trim_ascii_start().starts_with(b"{");
        let (format, json, bin) = if is_json {
            ("glTF", text, None)
        } else {
            let c = glb::split(path, bytes)?;
            ("binary glTF", c.json, c.bin)
        };
        let root = Root::from_slice(json).map_err(|e| {
            let message = e.to_string();
            malformed(
                path,
                format,
                Location::File,
                ProblemKind::GltfJson { message },
            )
        })?;
        let mut doc = Doc {
            path,
            format,
            root,
            buffers: Vec::new(),
        };
        let version = &doc.root.asset.version;
        if !version.starts_with("2.") {
            let kind = ProblemKind::Expected {
                expected: "glTF version 2.x".into(),
                found: version.clone(),
            };
            return Err(doc.err("asset.version".into(), kind));
        }
        if let Some(ext) = doc.root.extensions_required.first() {
            let what = format!("the required extension {ext}");
            let kind = ProblemKind::GltfUnsupported { what };
            return Err(doc.err("extensionsRequired".into(), kind));
        }
        for i in 0..doc.root.buffers.len() {
            let b = doc.buffer(i, bin)?;
            doc.buffers.push(b);
        }
        Ok(doc)
    }

    /// What the reader leaves out, as warnings.
    fn notes(&self) -> Vec<String> {
        let mut notes = Vec::new();
        if self.root.nodes.iter().any(|n| n.skin.is_some()) {
            notes.push("skinned meshes are read in their bind pose".into());
        }
        let morphs = self.root.meshes.iter().flat_map(|m| &m.primitives);
        if morphs.filter(|p| p.targets.is_some()).count() > 0 {
            notes.push("morph targets are left out: meshes are read at rest".into());
        }
        notes
    }

    /// Buffer `i`'s bytes, `byteLength` of them: the BIN chunk, a `data:` URI, or a file beside
    /// the document.
    fn buffer(&self, i: usize, bin: Option<&'a [u8]>) -> Result<Cow<'a, [u8]>, IoError> {
        let b = &self.root.buffers[i];
        let key = format!("buffers[{i}]");
        let len = b.byte_length.0;
        let data: Cow<'a, [u8]> = match b.uri.as_deref() {
            None => match bin {
                Some(bin) if i == 0 => Cow::Borrowed(bin),
                _ => {
                    let reason = format!("buffer {i} has no uri and is not the BIN chunk of a binary glTF (only buffer 0 of a .glb may be)");
                    return Err(self.err(key, ProblemKind::GlbChunk { reason }));
                }
            },
            Some(uri) if uri.starts_with("data:") => Cow::Owned(self.data_uri(&key, uri)?),
            Some(uri) => Cow::Owned(self.file(&key, uri, len)?),
        };
        if (data.len() as u64) < len {
            let kind = ProblemKind::GltfShort {
                what: format!("its byteLength of {len}"),
                needed: len,
                within: "the data".into(),
                available: data.len() as u64,
            };
            return Err(self.err(key, kind));
        }
        Ok(match data {
            Cow::Borrowed(d) => Cow::Borrowed(&d[..len as usize]),
            Cow::Owned(mut d) => {
                d.truncate(len as usize);
                Cow::Owned(d)
            }
        })
    }

    /// The bytes of a `data:...;base64,` URI.
    fn data_uri(&self, key: &str, uri: &str) -> Result<Vec<u8>, IoError> {
        use base64::Engine;
        let payload = uri.split_once(";base64,").map(|(_, p)| p);
        let decoded = payload.map(|p| base64::engine::general_purpose::STANDARD.decode(p));
        match decoded {
            Some(Ok(d)) => Ok(d),
            Some(Err(e)) => Err(self.err(
                format!("{key}.uri"),
                ProblemKind::Expected {
                    expected: "base64 data".into(),
                    found: e.to_string(),
                },
            )),
            None => Err(self.err(
                format!("{key}.uri"),
                ProblemKind::GltfUnsupported {
                    what: "a data: URI that is not base64".into(),
                },
            )),
        }
    }

    /// The first `len` bytes of the file a relative URI names, beside the document.
    fn file(&self, key: &str, uri: &str, len: u64) -> Result<Vec<u8>, IoError> {
        let key = format!("{key}.uri");
        let name = percent_encoding::percent_decode_str(uri).decode_utf8_lossy();
        if name.contains("://") || Path::new(name.as_ref()).is_absolute() {
            let what = format!("buffer uri '{uri}' (only data: URIs and relative file paths)");
            return Err(self.err(key, ProblemKind::GltfUnsupported { what }));
        }
        let dir = self.path.parent().unwrap_or(Path::new("."));
        let file = dir.join(name.as_ref());
        let shown = file.display().to_string();
        let cannot = |e: std::io::Error| {
            let reason = e.to_string();
            self.err(
                key.clone(),
                ProblemKind::GltfBufferFile {
                    file: shown.clone(),
                    reason,
                },
            )
        };
        let f = std::fs::File::open(&file).map_err(cannot)?;
        let size = f.metadata().map_err(cannot)?.len();
        if size < len {
            let kind = ProblemKind::GltfShort {
                what: format!("the buffer's byteLength of {len}"),
                needed: len,
                within: format!("the file {shown}"),
                available: size,
            };
            return Err(self.err(key, kind));
        }
        let mut data = Vec::with_capacity(len as usize);
        f.take(len).read_to_end(&mut data).map_err(cannot)?;
        Ok(data)
    }

    /// The (mesh, world matrix, node key) of every mesh the scene places.
    fn instances(&self, warnings: &mut Vec<String>) -> Result<Vec<Instance>, IoError> {
        let r = &self.root;
        if r.scene.is_none() && r.scenes.is_empty() && r.nodes.is_empty() {
            if !r.meshes.is_empty() {
                warnings.push("no nodes: every mesh is read once, as stored".into());
            }
            let all = (0..r.meshes.len()).map(|m| (m, Matrix4::identity(), String::new()));
            return Ok(all.collect());
        }
        let (roots, from) = self.root_nodes()?;
        let (out, hidden) = self.walk_nodes(roots, from)?;
        if hidden > 0 {
            warnings.push(format!("{hidden} meshes placed by nodes scaled to zero (hidden, e.g. animation frames not shown) are left out"));
        }
        Ok(out)
    }

    /// The nodes the scene starts from, and the key that lists them: the default scene's, the
    /// first scene's, or (no scene) every node that is no node's child.
    fn root_nodes(&self) -> Result<(Vec<usize>, String), IoError> {
        let r = &self.root;
        match (r.scene, r.scenes.first()) {
            (Some(s), _) => {
                let scene = r.scenes.get(s.value()).ok_or_else(|| {
                    self.missing("scene".into(), "scene", s.value(), r.scenes.len())
                })?;
                let key = format!("scenes[{}].nodes", s.value());
                Ok((scene.nodes.iter().map(|n| n.value()).collect(), key))
            }
            (None, Some(scene)) => {
                let nodes = scene.nodes.iter().map(|n| n.value()).collect();
                Ok((nodes, "scenes[0].nodes".into()))
            }
            (None, None) => {
                let mut child = vec![false; r.nodes.len()];
                let kids = r.nodes.iter().flat_map(|n| n.children.iter().flatten());
                for c in kids {
                    if let Some(c) = child.get_mut(c.value()) {
                        *c = true;
                    }
                }
                let roots = (0..r.nodes.len()).filter(|&n| !child[n]).collect();
                Ok((roots, "nodes".into()))
            }
        }
    }

    /// The node trees from `roots` (listed at the key `from`), depth first: the (mesh, world
    /// matrix, node key) of every mesh placed, and how many were hidden (scaled to zero).
    fn walk_nodes(
        &self,
        roots: Vec<usize>,
        from: String,
    ) -> Result<(Vec<Instance>, usize), IoError> {
        let r = &self.root;
        let mut out = Vec::new();
        let mut hidden = 0;
        let mut seen = vec![false; r.nodes.len()];
        let mut stack: Vec<(usize, Matrix4<f64>, String)> = roots
            .into_iter()
            .map(|n| (n, Matrix4::identity(), from.clone()))
            .rev()
            .collect();
        while let Some((n, parent, key)) = stack.pop() {
            let node = r
                .nodes
                .get(n)
                .ok_or_else(|| self.missing(key, "node", n, r.nodes.len()))?;
            let key = format!("nodes[{n}]");
            if std::mem::replace(&mut seen[n], true) {
                let kind = ProblemKind::Expected {
                    expected: "nodes that form trees (one parent each, no cycles)".into(),
                    found: format!("node {n} reached a second time"),
                };
                return Err(self.err(key, kind));
            }
            let world = parent * local_matrix(node);
            if let Some(bad) = world.iter().find(|v| !v.is_finite()) {
                let kind = ProblemKind::BinaryNonFinite { value: *bad };
                return Err(self.err(format!("{key} (its transform)"), kind));
            }
            if let Some(m) = node.mesh {
                if m.value() >= r.meshes.len() {
                    let k = format!("{key}.mesh");
                    return Err(self.missing(k, "mesh", m.value(), r.meshes.len()));
                }
                if world.fixed_view::<3, 3>(0, 0).determinant() == 0.0 {
                    hidden += 1;
                } else {
                    out.push((m.value(), world, key.clone()));
                }
            }
            let kids = node.children.iter().flatten().rev();
            stack.extend(kids.map(|c| (c.value(), world, format!("{key}.children"))));
        }
        Ok((out, hidden))
    }

    fn missing(&self, key: String, what: &str, index: usize, count: usize) -> IoError {
        let kind = ProblemKind::GltfMissing {
            what: what.into(),
            index: index as u64,
            count: count as u64,
        };
        self.err(key, kind)
    }

    /// The triangle primitives of mesh `m`, decoded and checked.
    fn mesh(&self, m: usize) -> Result<Vec<Primitive>, IoError> {
        let mesh = &self.root.meshes[m];
        let mut out = Vec::with_capacity(mesh.primitives.len());
        for (i, p) in mesh.primitives.iter().enumerate() {
            let key = format!("meshes[{m}].primitives[{i}]");
            match p.mode {
                Checked::Valid(Mode::Triangles) => {}
                Checked::Valid(mode) => {
                    let mode = format!("{} ({mode:?})", mode.as_gl_enum());
                    return Err(self.err(format!("{key}.mode"), ProblemKind::GltfMode { mode }));
                }
                Checked::Invalid => {
                    let mode = "invalid".into();
                    return Err(self.err(format!("{key}.mode"), ProblemKind::GltfMode { mode }));
                }
            }
            let Some(pos) = p.attributes.get(&Checked::Valid(Semantic::Positions)) else {
                let kind = ProblemKind::Expected {
                    expected: "a POSITION attribute".into(),
                    found: "none".into(),
                };
                return Err(self.err(format!("{key}.attributes"), kind));
            };
            let positions = self.positions(pos.value(), &format!("{key}.attributes.POSITION"))?;
            let n = positions.len() as u64;
            let corners = match p.indices {
                Some(a) => self.indices(a.value(), &format!("{key}.indices"), n)?,
                None => (0..n as u32).collect(),
            };
            if corners.len() % 3 != 0 {
                let kind = ProblemKind::GltfTriangleCount {
                    count: corners.len() as u64,
                };
                return Err(self.err(key, kind));
            }
            let triangles = corners
                .chunks_exact(3)
                .map(|t| [t[0], t[1], t[2]])
                .collect();
            out.push(Primitive {
                positions,
                triangles,
            });
        }
        Ok(out)
    }

    /// Accessor `a`'s elements as byte slices of `size` bytes each, every bound checked.
    fn elements(&self, a: usize, key: &str, size: usize) -> Result<Vec<&[u8]>, IoError> {
        let r = &self.root;
        let acc = r
            .accessors
            .get(a)
            .ok_or_else(|| self.missing(key.into(), "accessor", a, r.accessors.len()))?;
        let akey = format!("accessors[{a}]");
        if acc.sparse.is_some() {
            let what = "a sparse accessor".into();
            return Err(self.err(akey, ProblemKind::GltfUnsupported { what }));
        }
        let Some(v) = acc.buffer_view.map(|v| v.value()) else {
            let what = "an accessor without a bufferView (all zeros)".into();
            return Err(self.err(akey, ProblemKind::GltfUnsupported { what }));
        };
        let vkey = format!("{akey}.bufferView");
        let view = r
            .buffer_views
            .get(v)
            .ok_or_else(|| self.missing(vkey, "bufferView", v, r.buffer_views.len()))?;
        let b = view.buffer.value();
        let bkey = format!("bufferViews[{v}].buffer");
        let buffer = self
            .buffers
            .get(b)
            .ok_or_else(|| self.missing(bkey, "buffer", b, self.buffers.len()))?;
        let start = view.byte_offset.map_or(0, |o| o.0);
        let end = u128::from(start) + u128::from(view.byte_length.0);
        if end > buffer.len() as u128 {
            let kind = ProblemKind::GltfShort {
                what: format!("bufferView {v} (bytes {start} to {end})"),
                needed: end.min(u128::from(u64::MAX)) as u64,
                within: format!("buffer {b}"),
                available: buffer.len() as u64,
            };
            return Err(self.err(format!("bufferViews[{v}]"), kind));
        }
        let bytes = &buffer[start as usize..end as usize];
        let stride = view.byte_stride.map_or(size, |s| s.0);
        if stride < size {
            let kind = ProblemKind::Expected {
                expected: format!("a byteStride of at least {size} (one element)"),
                found: stride.to_string(),
            };
            return Err(self.err(format!("bufferViews[{v}].byteStride"), kind));
        }
        let (count, offset) = (acc.count.0, acc.byte_offset.map_or(0, |o| o.0));
        let needed = match count {
            0 => 0,
            c => u128::from(offset) + u128::from(c - 1) * stride as u128 + size as u128,
        };
        if needed > bytes.len() as u128 {
            let kind = ProblemKind::GltfShort {
                what: format!(
                    "{count} elements of {size} bytes (stride {stride}) from byte {offset}"
                ),
                needed: needed.min(u128::from(u64::MAX)) as u64,
                within: format!("bufferView {v}"),
                available: bytes.len() as u64,
            };
            return Err(self.err(akey, kind));
        }
        let at = |k: u64| offset as usize + k as usize * stride;
        Ok((0..count).map(|k| &bytes[at(k)..at(k) + size]).collect())
    }

    /// The component type and type of accessor `a` (which exists).
    fn kind(&self, a: usize) -> (Option<ComponentType>, Option<Type>) {
        let acc = &self.root.accessors[a];
        let c = match acc.component_type {
            Checked::Valid(c) => Some(c.0),
            Checked::Invalid => None,
        };
        let t = match acc.type_ {
            Checked::Valid(t) => Some(t),
            Checked::Invalid => None,
        };
        (c, t)
    }

    /// A POSITION accessor: float VEC3, every coordinate finite.
    fn positions(&self, a: usize, key: &str) -> Result<Vec<[f32; 3]>, IoError> {
        if a >= self.root.accessors.len() {
            return Err(self.missing(key.into(), "accessor", a, self.root.accessors.len()));
        }
        if self.kind(a) != (Some(ComponentType::F32), Some(Type::Vec3)) {
            let (c, t) = self.kind(a);
            let kind = ProblemKind::Expected {
                expected: "POSITION as FLOAT VEC3".into(),
                found: format!("{c:?} {t:?}"),
            };
            return Err(self.err(format!("accessors[{a}] ({key})"), kind));
        }
        let mut out = Vec::new();
        for (k, e) in self.elements(a, key, 12)?.into_iter().enumerate() {
            let p: [f32; 3] = std::array::from_fn(|i| {
                f32::from_le_bytes(e[4 * i..4 * i + 4].try_into().expect("4 bytes"))
            });
            if let Some(bad) = p.iter().find(|c| !c.is_finite()) {
                let kind = ProblemKind::BinaryNonFinite {
                    value: f64::from(*bad),
                };
                return Err(self.err(format!("accessors[{a}] element {k} ({key})"), kind));
            }
            out.push(p);
        }
        Ok(out)
    }

    /// An index accessor: unsigned byte, short or int SCALAR, every index below `n`.
    fn indices(&self, a: usize, key: &str, n: u64) -> Result<Vec<u32>, IoError> {
        if a >= self.root.accessors.len() {
            return Err(self.missing(key.into(), "accessor", a, self.root.accessors.len()));
        }
        let size = match self.kind(a) {
            (Some(ComponentType::U8), Some(Type::Scalar)) => 1,
            (Some(ComponentType::U16), Some(Type::Scalar)) => 2,
            (Some(ComponentType::U32), Some(Type::Scalar)) => 4,
            (c, t) => {
                let kind = ProblemKind::Expected {
                    expected: "indices as UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT SCALAR"
                        .into(),
                    found: format!("{c:?} {t:?}"),
                };
                return Err(self.err(format!("accessors[{a}] ({key})"), kind));
            }
        };
        let mut out = Vec::new();
        for (k, e) in self.elements(a, key, size)?.into_iter().enumerate() {
            let i = match size {
                1 => u32::from(e[0]),
                2 => u32::from(u16::from_le_bytes([e[0], e[1]])),
                _ => u32::from_le_bytes([e[0], e[1], e[2], e[3]]),
            };
            if u64::from(i) >= n {
                let kind = ProblemKind::IndexOutOfRange {
                    index: i64::from(i),
                    count: n,
                };
                return Err(self.err(format!("accessors[{a}] element {k} ({key})"), kind));
            }
            out.push(i);
        }
        Ok(out)
    }
}
