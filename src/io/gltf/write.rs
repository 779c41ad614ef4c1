//! Writing glTF 2.0: several named meshes in one file, with normals, optional per-vertex
//! colours, and optional frames played as an animation.
//!
//! Each [`Part`] becomes a node with its own mesh: `POSITION` (32-bit floats, with the `min`
//! and `max` the specification requires), `NORMAL` (area-weighted, see [`vertex_normals`]),
//! `COLOR_0` when the part has colours (RGBA floats in 0..=1; the material's base colour is
//! then white, so the colours show as given), and `u32` indices. Cloth is double-sided.
//!
//! **Frames.** Each [`Frame`] becomes a node whose children are its parts. One animation,
//! `frames`, shows one frame at a time: frame `k`'s node has scale 1 from its time `t_k` until
//! `t_{k+1}` and scale 0 otherwise, keyed with `STEP` interpolation (no blending between
//! frames). Without the animation (a static viewer) only the last frame shows: the others have
//! scale 0. Why nodes and not morph targets: a frame is then a plain mesh with its own normals
//! and colours (core glTF morph targets move positions and normals only, so strain colours
//! could not follow the frames), and the keys grow with the frames (three per frame) where a
//! weights animation grows with their square. The Khronos validator accepts it without
//! warnings, and three.js and Blender play scale animations with `STEP`.

use super::glb;
use crate::io::{stage, IoError, Staged};
use crate::math::Point3;
use crate::mesh::TriMesh;
use gltf_json as json;
use json::accessor::{ComponentType, GenericComponentType, Type};
use json::buffer::Target;
use json::validation::{Checked::Valid, USize64};
use json::Index;
use serde_json::{json as value, Value};
use std::collections::HashMap;
use std::path::Path;

/// How a part is shown.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Surface {
    /// Cloth: double-sided, a light fabric colour.
    Cloth,
    /// A rigid object: single-sided, grey.
    Solid,
}

/// One named mesh of a scene.
#[derive(Debug, Clone)]
pub struct Part {
    /// Its name (the node's and the mesh's).
    pub name: String,
    /// The mesh, in the scene's frame and units.
    pub mesh: TriMesh,
    /// One linear RGBA colour per vertex, each channel in 0..=1 (`None`: the material's colour).
    pub colors: Option<Vec<[f32; 4]>>,
    /// How it is shown.
    pub surface: Surface,
}

impl Part {
    /// A part without colours.
    pub fn new(name: impl Into<String>, mesh: TriMesh, surface: Surface) -> Part {
        Part {
            name: name.into(),
            mesh,
            colors: None,
            surface,
        }
    }
}

/// The parts at one moment of an animation.
#[derive(Debug, Clone)]
pub struct Frame {
    /// Its time, s (at least 0, increasing from frame to frame).
    pub time: f64,
    /// The parts as they are then.
    pub parts: Vec<Part>,
}

/// What one glTF file holds.
#[derive(Debug, Clone, Default)]
pub struct Scene {
    /// Parts shown throughout.
    pub parts: Vec<Part>,
    /// Frames shown one at a time by the animation (empty: no animation).
    pub frames: Vec<Frame>,
}

/// Area-weighted vertex normals: `n_v = s_v / |s_v|` with `s_v` the sum of the cross products
/// `(b - a) x (c - a)` (twice the area times the unit normal) of the faces at `v`; `(0, 0, 1)`
/// where the sum vanishes (an unused vertex, or faces of zero area).
///
/// ```
/// use drapekit::io::gltf::vertex_normals;
/// use drapekit::math::Point3;
/// use drapekit::mesh::TriMesh;
/// // Half a unit square in z = 0 (area 1/2, normal +z) hinged to a triangle of area 1 facing +x.
/// let p = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 2.0]];
/// let mesh = TriMesh::new(p.map(Point3::from).to_vec(), vec![[0, 1, 2], [0, 2, 3]]);
/// let n = vertex_normals(&mesh);
/// // The hinge: (0, 0, 1) + (2, 0, 0), normalised: (2, 0, 1) / 5^0.5.
/// assert!((n[0][0] - 0.894_427_2).abs() < 1e-6 && n[0][1] == 0.0);
/// assert!((n[0][2] - 0.447_213_6).abs() < 1e-6);
/// assert_eq!(n[1], [0.0, 0.0, 1.0]);
/// assert_eq!(n[3], [1.0, 0.0, 0.0]);
/// ```
pub fn vertex_normals(mesh: &TriMesh) -> Vec<[f32; 3]> {
    let mut sum = vec![crate::math::Vec3::zeros(); mesh.positions.len()];
    for (f, face) in mesh.faces.iter().enumerate() {
        let c = mesh.face_cross(f);
        for &v in face {
            sum[v as usize] += c;
        }
    }
    sum.iter()
        .map(|s| match s.try_normalize(0.0) {
            Some(n) if n.iter().all(|c| c.is_finite()) => [n.x as f32, n.y as f32, n.z as f32],
            _ => [0.0, 0.0, 1.0],
        })
        .collect()
}

/// Writes `scene` to `path` atomically (GLB, or JSON with the buffer in a `data:` URI when the
/// extension is `.gltf`), refusing to overwrite any of `inputs`.
pub fn write_scene(path: &Path, scene: &Scene, inputs: &[&Path]) -> Result<(), IoError> {
    stage_scene(path, scene, inputs)?.commit()
}

/// Writes `scene` for `path` into a temporary file beside it, left staged (see `io::commit`).
pub fn stage_scene(path: &Path, scene: &Scene, inputs: &[&Path]) -> Result<Staged, IoError> {
    check(path, scene)?;
    let embed = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("gltf"));
    let bytes = encode(scene, embed).map_err(|reason| IoError::Write {
        path: path.to_path_buf(),
        source: std::io::Error::other(reason),
    })?;
    stage(path, inputs, |w| std::io::Write::write_all(w, &bytes))
}

/// Refuses what glTF cannot hold: non-finite or beyond-f32 coordinates, colours that do not
/// match their mesh or leave 0..=1, frame times that are negative or do not increase.
fn check(path: &Path, scene: &Scene) -> Result<(), IoError> {
    let frames = scene.frames.iter().flat_map(|f| &f.parts);
    for part in scene.parts.iter().chain(frames) {
        check_part(path, part)?;
    }
    let times: Vec<f32> = scene.frames.iter().map(|f| f.time as f32).collect();
    let bad = |reason: String| IoError::BadAnimation {
        path: path.to_path_buf(),
        reason,
    };
    if let Some(t) = times.iter().find(|t| !(t.is_finite() && **t >= 0.0)) {
        return Err(bad(format!(
            "frame time {t} s is not a finite time of 0 s or more"
        )));
    }
    if let Some(k) = times.windows(2).position(|w| w[1] <= w[0]) {
        let (a, b) = (times[k], times[k + 1]);
        return Err(bad(format!(
            "frame {} at {b} s does not come after frame {k} at {a} s (as 32-bit floats)",
            k + 1
        )));
    }
    Ok(())
}

fn check_part(path: &Path, part: &Part) -> Result<(), IoError> {
    if let Some(value) = crate::io::stl::below_f32(&part.mesh) {
        let path = path.to_path_buf();
        return Err(IoError::TooSmallForFloat { path, value });
    }
    for (v, p) in part.mesh.positions.iter().enumerate() {
        if !p.iter().all(|c| c.is_finite()) {
            let path = path.to_path_buf();
            return Err(IoError::NonFinite { path, vertex: v });
        }
        if let Some(&value) = p.iter().find(|c| c.abs() > f64::from(f32::MAX)) {
            let path = path.to_path_buf();
            return Err(IoError::OutOfFloatRange {
                path,
                vertex: v,
                value,
            });
        }
    }
    let Some(colors) = &part.colors else {
        return Ok(());
    };
    let bad = |what: String| IoError::BadColors {
        path: path.to_path_buf(),
        reason: format!("the colours of '{}' {what}", part.name),
    };
    if colors.len() != part.mesh.positions.len() {
        let (c, v) = (colors.len(), part.mesh.positions.len());
        return Err(bad(format!("number {c}, for {v} vertices")));
    }
    if let Some(v) = colors
        .iter()
        .position(|c| !c.iter().all(|x| (0.0..=1.0).contains(x)))
    {
        return Err(bad(format!("leave 0..=1 at vertex {v}: {:?}", colors[v])));
    }
    Ok(())
}

/// The file's bytes: GLB, or JSON with a `data:` URI (`embed`).
fn encode(scene: &Scene, embed: bool) -> Result<Vec<u8>, String> {
    let mut b = Builder::default();
    let mut roots: Vec<Index<json::Node>> = scene.parts.iter().map(|p| b.part(p, None)).collect();
    let last = scene.frames.len().saturating_sub(1);
    let mut frame_nodes = Vec::new();
    let mut shared: Vec<Option<Index<json::Accessor>>> = Vec::new();
    for (k, frame) in scene.frames.iter().enumerate() {
        let children = frame.parts.iter().enumerate().map(|(i, p)| {
            // A part whose faces are the first frame's shares its indices.
            let first = scene.frames[0]
                .parts
                .get(i)
                .filter(|f| f.mesh.faces == p.mesh.faces);
            let idx = first.and(shared.get(i).copied().flatten());
            let node = b.part(p, idx);
            if k == 0 {
                shared.push(b.last_indices);
            }
            node
        });
        let children: Vec<_> = children.collect();
        let node = json::Node {
            name: Some(format!("frame {k} (t = {} s)", frame.time)),
            children: Some(children),
            scale: (k != last).then_some([0.0; 3]),
            ..Default::default()
        };
        let n = b.root.push(node);
        frame_nodes.push(n);
        roots.push(n);
    }
    if scene.frames.len() > 1 {
        b.animation(scene, &frame_nodes);
    }
    b.root.scenes.push(json::Scene {
        extensions: None,
        extras: Default::default(),
        name: Some("drapekit".into()),
        nodes: roots,
    });
    b.root.scene = Some(Index::new(0));
    b.finish(embed)
}

/// A document being built: its JSON root and its one binary buffer.
#[derive(Default)]
struct Builder {
    root: json::Root,
    bin: Vec<u8>,
    materials: HashMap<(Surface, bool), Index<json::Material>>,
    last_indices: Option<Index<json::Accessor>>,
}

impl Builder {
    /// A buffer view over `bytes`, appended at a 4-byte boundary.
    fn view(&mut self, bytes: &[u8], target: Option<Target>) -> Index<json::buffer::View> {
        self.bin.resize(self.bin.len().next_multiple_of(4), 0);
        let offset = self.bin.len();
        self.bin.extend_from_slice(bytes);
        self.root.push(json::buffer::View {
            buffer: Index::new(0),
            byte_length: USize64::from(bytes.len()),
            byte_offset: Some(USize64::from(offset)),
            byte_stride: None,
            name: None,
            target: target.map(Valid),
            extensions: None,
            extras: Default::default(),
        })
    }

    /// An accessor over `floats` (little-endian f32), `width` to an element, with min and max.
    fn floats(
        &mut self,
        floats: &[f32],
        ty: Type,
        target: Option<Target>,
        bounds: bool,
    ) -> Index<json::Accessor> {
        let width = ty.multiplicity();
        let bytes: Vec<u8> = floats.iter().flat_map(|f| f.to_le_bytes()).collect();
        let view = self.view(&bytes, target);
        let (min, max) = if bounds {
            min_max(floats, width)
        } else {
            (None, None)
        };
        self.accessor(view, floats.len() / width, ComponentType::F32, ty, min, max)
    }

    fn accessor(
        &mut self,
        view: Index<json::buffer::View>,
        count: usize,
        component: ComponentType,
        ty: Type,
        min: Option<Value>,
        max: Option<Value>,
    ) -> Index<json::Accessor> {
        self.root.push(json::Accessor {
            buffer_view: Some(view),
            byte_offset: None,
            count: USize64::from(count),
            component_type: Valid(GenericComponentType(component)),
            extensions: None,
            extras: Default::default(),
            type_: Valid(ty),
            min,
            max,
            name: None,
            normalized: false,
            sparse: None,
        })
    }

    /// The material for a surface, with (white) or without vertex colours.
    fn material(&mut self, surface: Surface, colored: bool) -> Index<json::Material> {
        if let Some(m) = self.materials.get(&(surface, colored)) {
            return *m;
        }
        let (name, base, double) = match surface {
            Surface::Cloth => ("cloth", [0.82, 0.78, 0.70, 1.0], true),
            Surface::Solid => ("object", [0.55, 0.57, 0.60, 1.0], false),
        };
        let base = if colored { [1.0; 4] } else { base };
        let m: json::Material = serde_json::from_value(value!({
            "name": name,
            "doubleSided": double,
            "pbrMetallicRoughness": {"baseColorFactor": base, "metallicFactor": 0.0, "roughnessFactor": 0.9},
        }))
        .expect("a valid material");
        let i = self.root.push(m);
        self.materials.insert((surface, colored), i);
        i
    }

    /// A node with `part`'s mesh; `indices` reuses an index accessor with the same faces.
    fn part(&mut self, part: &Part, indices: Option<Index<json::Accessor>>) -> Index<json::Node> {
        let m = &part.mesh;
        if m.faces.is_empty() {
            // glTF has no empty accessors: a part without faces is a node without a mesh.
            let name = Some(part.name.clone());
            return self.root.push(json::Node {
                name,
                ..Default::default()
            });
        }
        let pos: Vec<f32> = m.positions.iter().flat_map(to_f32).collect();
        let normals: Vec<f32> = vertex_normals(m).into_iter().flatten().collect();
        let mut attributes = std::collections::BTreeMap::new();
        let array = Some(Target::ArrayBuffer);
        let p = self.floats(&pos, Type::Vec3, array, true);
        attributes.insert(Valid(json::mesh::Semantic::Positions), p);
        let n = self.floats(&normals, Type::Vec3, array, false);
        attributes.insert(Valid(json::mesh::Semantic::Normals), n);
        if let Some(c) = &part.colors {
            let flat: Vec<f32> = c.iter().flatten().copied().collect();
            let c = self.floats(&flat, Type::Vec4, array, false);
            attributes.insert(Valid(json::mesh::Semantic::Colors(0)), c);
        }
        let indices = indices.unwrap_or_else(|| {
            let bytes: Vec<u8> = m
                .faces
                .iter()
                .flatten()
                .flat_map(|i| i.to_le_bytes())
                .collect();
            let view = self.view(&bytes, Some(Target::ElementArrayBuffer));
            self.accessor(
                view,
                m.faces.len() * 3,
                ComponentType::U32,
                Type::Scalar,
                None,
                None,
            )
        });
        self.last_indices = Some(indices);
        let material = self.material(part.surface, part.colors.is_some());
        let mesh = self.root.push(json::Mesh {
            extensions: None,
            extras: Default::default(),
            name: Some(part.name.clone()),
            primitives: vec![json::mesh::Primitive {
                attributes,
                extensions: None,
                extras: Default::default(),
                indices: Some(indices),
                material: Some(material),
                mode: Valid(json::mesh::Mode::Triangles),
                targets: None,
            }],
            weights: None,
        });
        self.root.push(json::Node {
            mesh: Some(mesh),
            name: Some(part.name.clone()),
            ..Default::default()
        })
    }

    /// The `frames` animation: frame `k` at scale 1 from `t_k` to `t_{k+1}`, else 0 (STEP).
    fn animation(&mut self, scene: &Scene, nodes: &[Index<json::Node>]) {
        let t: Vec<f32> = scene.frames.iter().map(|f| f.time as f32).collect();
        let last = t.len() - 1;
        let mut channels = Vec::new();
        let mut samplers = Vec::new();
        for (k, node) in nodes.iter().enumerate() {
            let (times, scales): (Vec<f32>, Vec<f32>) = match k {
                0 => (vec![t[0], t[1]], vec![1.0, 0.0]),
                k if k == last => (vec![t[0], t[k]], vec![0.0, 1.0]),
                k => (vec![t[0], t[k], t[k + 1]], vec![0.0, 1.0, 0.0]),
            };
            let scales: Vec<f32> = scales.iter().flat_map(|s| [*s; 3]).collect();
            let input = self.floats(&times, Type::Scalar, None, true);
            let output = self.floats(&scales, Type::Vec3, None, false);
            channels.push(json::animation::Channel {
                sampler: Index::new(samplers.len() as u32),
                target: json::animation::Target {
                    extensions: None,
                    extras: Default::default(),
                    node: *node,
                    path: Valid(json::animation::Property::Scale),
                },
                extensions: None,
                extras: Default::default(),
            });
            samplers.push(json::animation::Sampler {
                extensions: None,
                extras: Default::default(),
                input,
                interpolation: Valid(json::animation::Interpolation::Step),
                output,
            });
        }
        self.root.push(json::Animation {
            extensions: None,
            extras: Default::default(),
            channels,
            name: Some("frames".into()),
            samplers,
        });
    }

    /// The document: the buffer declared, then GLB bytes or JSON with a `data:` URI.
    fn finish(mut self, embed: bool) -> Result<Vec<u8>, String> {
        self.root.asset = json::Asset {
            generator: Some(format!("drapekit {}", env!("CARGO_PKG_VERSION"))),
            ..Default::default()
        };
        if !self.bin.is_empty() {
            self.bin.resize(self.bin.len().next_multiple_of(4), 0);
            let uri = embed.then(|| {
                use base64::Engine;
                let data = base64::engine::general_purpose::STANDARD.encode(&self.bin);
                format!("data:application/octet-stream;base64,{data}")
            });
            self.root.push(json::Buffer {
                byte_length: USize64::from(self.bin.len()),
                name: None,
                uri,
                extensions: None,
                extras: Default::default(),
            });
        }
        let text = self.root.to_vec().map_err(|e| e.to_string())?;
        if embed {
            Ok(text)
        } else {
            glb::join(&text, &self.bin)
        }
    }
}

/// The componentwise min and max of `floats` taken `width` at a time (as JSON arrays).
fn min_max(floats: &[f32], width: usize) -> (Option<Value>, Option<Value>) {
    if floats.is_empty() {
        return (None, None);
    }
    let mut lo = vec![f32::INFINITY; width];
    let mut hi = vec![f32::NEG_INFINITY; width];
    for e in floats.chunks_exact(width) {
        for i in 0..width {
            lo[i] = lo[i].min(e[i]);
            hi[i] = hi[i].max(e[i]);
        }
    }
    (Some(value!(lo)), Some(value!(hi)))
}

/// A scene of one part named `name` (the mesh alone: `convert` to `.glb` or `.gltf`).
pub fn single(name: &str, mesh: &TriMesh) -> Scene {
    Scene {
        parts: vec![Part::new(name, mesh.clone(), Surface::Solid)],
        frames: Vec::new(),
    }
}

/// `p` as three 32-bit floats.
pub fn to_f32(p: &Point3) -> [f32; 3] {
    [p.x as f32, p.y as f32, p.z as f32]
}
