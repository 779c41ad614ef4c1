//! Pictures of meshes: shaded, correctly occluded, coloured by a quantity with a legend.
//!
//! A picture is one panel (a named [`View`]) or the paper's three projections side by side
//! (XY, XZ, YZ, at one scale), and a legend strip at the right when the first meshes are
//! coloured by a quantity. Each panel is drawn in three steps:
//!
//! 1. **Project** ([`camera`]): orthographic, `(x, y) = (c + s (p·r - m_r), c' - s (p·u - m_u))`
//!    with `s` pixels per unit chosen so the whole scene (or, for an animation, every frame)
//!    fits the panel; depth `p·f`.
//! 2. **Rasterise** ([`raster`]): every triangle of every mesh, in fixed point with the
//!    top-left rule, into a depth buffer: each pixel keeps its nearest fragment, so a mesh
//!    behind another is hidden however the meshes are ordered (no painter's sort).
//! 3. **Shade** ([`shade`]): Lambert plus ambient, `c (A + (1 - A) max(0, n·l))`, the base
//!    colour `c` being the mesh's colour or, for a coloured mesh, the [`colormap`] colour of
//!    its per-vertex value interpolated at the pixel.
//!
//! Per-vertex quantities: [`strain::vertex_strain`] (from the rest coordinates drape outputs
//! carry), [`field::distances`] (the fit map) and [`field::contact`]. Pictures are encoded by
//! [`image`] (PNG, APNG, GIF). Every step is deterministic: the same meshes and options give
//! the same pixels whatever the thread count.

pub mod camera;
pub mod colormap;
pub mod field;
pub mod font;
pub mod image;
pub mod raster;
pub mod shade;
pub mod strain;

pub use camera::{Camera, View};
pub use colormap::ColourScale;
pub use image::{Image, Rgb};
pub use shade::Shading;

use crate::math::{Point3, Vec3};
use crate::mesh::transform::Up;
use crate::mesh::TriMesh;
use rayon::prelude::*;

/// The smallest side of a picture or panel, px.
pub const MIN_SIDE: u32 = 16;
/// The largest side of a picture, px (GIF's limit is 65,535).
pub const MAX_SIDE: u32 = 8192;

/// What stops a picture.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RenderError {
    /// A side out of range.
    #[error("picture size {width} x {height} px: each side must be {MIN_SIDE} to {MAX_SIDE} px")]
    Size {
        /// Width asked for.
        width: u32,
        /// Height asked for.
        height: u32,
    },
    /// Too narrow for its panels and legend.
    #[error("a picture {width} px wide has no room for {panels} panel(s) of at least {MIN_SIDE} px beside a {legend} px legend")]
    TooNarrow {
        /// Width asked for.
        width: u32,
        /// Panels.
        panels: u32,
        /// Legend width (0: none).
        legend: u32,
    },
    /// No faces at all.
    #[error("nothing to draw: no mesh has a face")]
    Empty,
    /// Values not one per vertex.
    #[error("mesh {item}: {values} values for {vertices} vertices")]
    ValueCount {
        /// The mesh (0-based, in the order given).
        item: usize,
        /// Values given.
        values: usize,
        /// Its vertices.
        vertices: usize,
    },
    /// A value is NaN or infinite.
    #[error("mesh {item}: the value of vertex {vertex} is not finite")]
    NonFiniteValue {
        /// The mesh.
        item: usize,
        /// The vertex.
        vertex: usize,
    },
}

/// One panel or the three projections.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Layout {
    /// One view filling the picture.
    View(View),
    /// XY, XZ and YZ side by side, at one scale.
    Projections,
}

impl Default for Layout {
    fn default() -> Layout {
        Layout::View(View::Iso)
    }
}

impl std::str::FromStr for Layout {
    type Err = String;
    fn from_str(s: &str) -> Result<Layout, String> {
        if s.eq_ignore_ascii_case("projections") {
            Ok(Layout::Projections)
        } else {
            s.parse().map(Layout::View)
        }
    }
}

impl Layout {
    /// The views, left to right.
    pub fn views(self) -> Vec<View> {
        match self {
            Layout::View(v) => vec![v],
            Layout::Projections => vec![View::Xy, View::Xz, View::Yz],
        }
    }
}

/// How to draw a picture.
#[derive(Debug, Clone, PartialEq)]
pub struct RenderOptions {
    /// Width, px (default 800).
    pub width: u32,
    /// Height, px (default 600).
    pub height: u32,
    /// The view or the projections (default: iso).
    pub layout: Layout,
    /// The scene's up axis, for the named views (default z).
    pub up: Up,
    /// Background colour (default white).
    pub background: Rgb,
    /// Flat or smooth normals (default smooth).
    pub shading: Shading,
    /// How values become colours, and the legend (default none: every mesh in its colour).
    pub scale: Option<ColourScale>,
}

impl Default for RenderOptions {
    fn default() -> RenderOptions {
        RenderOptions {
            width: 800,
            height: 600,
            layout: Layout::default(),
            up: Up::Z,
            background: [255, 255, 255],
            shading: Shading::Smooth,
            scale: None,
        }
    }
}

/// A mesh to draw.
#[derive(Debug, Clone, Copy)]
pub struct Item<'a> {
    /// The mesh.
    pub mesh: &'a TriMesh,
    /// Its colour.
    pub colour: Rgb,
    /// One value per vertex, coloured through [`RenderOptions::scale`] instead of `colour`.
    pub values: Option<&'a [f64]>,
    /// Drawn this much nearer the camera (length units; 0 for objects). A cloth at rest a
    /// fabric thickness above a faceted body is pierced by the facets' ridges wherever its
    /// own triangles span one (a 2 cm triangle over a 6 degree ridge sags 0.5 mm below it,
    /// more than the 0.3 mm of cotton): lifting the cloth by [`LIFT`] of the scene keeps
    /// the body from showing through in spots.
    pub lift: f64,
}

/// The default lift of a cloth, as a fraction of the scene's bounding-box diagonal.
pub const LIFT: f64 = 0.002;

impl<'a> Item<'a> {
    /// An object: its colour, no lift.
    pub fn object(mesh: &'a TriMesh, colour: Rgb) -> Item<'a> {
        Item {
            mesh,
            colour,
            values: None,
            lift: 0.0,
        }
    }

    /// A cloth: its colour or values, lifted by `lift`.
    pub fn cloth(mesh: &'a TriMesh, colour: Rgb, values: Option<&'a [f64]>, lift: f64) -> Item<'a> {
        Item {
            mesh,
            colour,
            values,
            lift,
        }
    }
}

/// [`LIFT`] times the diagonal of the box around `points` (0 for none).
pub fn default_lift<'a>(points: impl Iterator<Item = &'a Point3>) -> f64 {
    let mut b: Option<crate::math::Aabb> = None;
    for p in points {
        match &mut b {
            Some(b) => b.include(p),
            None => b = crate::math::Aabb::of_points(std::slice::from_ref(p)),
        }
    }
    b.map_or(0.0, |b| LIFT * b.diagonal())
}

/// The cameras of a picture and where its panels and legend go.
#[derive(Debug, Clone, PartialEq)]
pub struct Framing {
    /// One per panel, left to right.
    pub cameras: Vec<Camera>,
    /// Where the legend strip starts (`None`: no legend).
    pub legend_x: Option<u32>,
}

impl RenderOptions {
    /// Checks the picture's size, and its width against the panels and the legend (a scale's
    /// range does not matter), so a command can refuse them before reading its inputs.
    ///
    /// ```
    /// use drapekit::render::{Layout, RenderOptions};
    /// let opts = RenderOptions { width: 40, layout: Layout::Projections, ..Default::default() };
    /// assert!(opts.check_size().is_err());
    /// assert!(RenderOptions::default().check_size().is_ok());
    /// ```
    pub fn check_size(&self) -> Result<(), RenderError> {
        self.panels().map(|_| ())
    }

    /// The panel size and the legend's place, after checking the sizes.
    fn panels(&self) -> Result<([u32; 2], Option<u32>), RenderError> {
        let (w, h) = (self.width, self.height);
        if !(MIN_SIDE..=MAX_SIDE).contains(&w) || !(MIN_SIDE..=MAX_SIDE).contains(&h) {
            return Err(RenderError::Size {
                width: w,
                height: h,
            });
        }
        let legend = self.scale.as_ref().map_or(0, |_| colormap::legend_width(h));
        let n = self.layout.views().len() as u32;
        let panel = w.saturating_sub(legend) / n;
        if panel < MIN_SIDE {
            return Err(RenderError::TooNarrow {
                width: w,
                panels: n,
                legend,
            });
        }
        Ok(([panel, h], self.scale.as_ref().map(|_| w - legend)))
    }
}

/// Frames the points `points()` yields (called once per view): cameras that fit them all.
pub fn frame<'a, I>(opts: &RenderOptions, points: impl Fn() -> I) -> Result<Framing, RenderError>
where
    I: Iterator<Item = &'a Point3>,
{
    let (panel, legend_x) = opts.panels()?;
    Ok(Framing {
        cameras: camera::fit(&opts.layout.views(), opts.up, panel, points),
        legend_x,
    })
}

/// Frames and draws `items`.
pub fn render_fitted(items: &[Item], opts: &RenderOptions) -> Result<Image, RenderError> {
    let framing = frame(opts, || items.iter().flat_map(|i| i.mesh.positions.iter()))?;
    render(items, &framing, opts)
}

/// Checks the items: some face to draw, values one per vertex and finite ([`render`] checks
/// them too; an animation checks every frame before it writes any).
pub fn check(items: &[Item]) -> Result<(), RenderError> {
    if items.iter().all(|i| i.mesh.faces.is_empty()) {
        return Err(RenderError::Empty);
    }
    for (k, it) in items.iter().enumerate() {
        let Some(v) = it.values else { continue };
        if v.len() != it.mesh.positions.len() {
            return Err(RenderError::ValueCount {
                item: k,
                values: v.len(),
                vertices: it.mesh.positions.len(),
            });
        }
        if let Some(vertex) = v.iter().position(|x| !x.is_finite()) {
            return Err(RenderError::NonFiniteValue { item: k, vertex });
        }
    }
    Ok(())
}

/// Draws `items` with the cameras of `framing` (from [`frame`] with the same options).
pub fn render(
    items: &[Item],
    framing: &Framing,
    opts: &RenderOptions,
) -> Result<Image, RenderError> {
    check(items)?;
    let mut img = Image::new(opts.width, opts.height, opts.background);
    let ink = if colormap::luminance(opts.background) > 128.0 {
        [0, 0, 0]
    } else {
        [255, 255, 255]
    };
    let normals: Vec<Normals> = items
        .iter()
        .map(|i| Normals::of(i.mesh, opts.shading))
        .collect();
    for (k, cam) in framing.cameras.iter().enumerate() {
        let panel = draw_panel(items, &normals, cam, opts);
        let x0 = k as u32 * cam.size[0];
        for y in 0..cam.size[1] {
            for x in 0..cam.size[0] {
                if let Some(c) = panel[(y * cam.size[0] + x) as usize] {
                    img.put(i64::from(x0 + x), i64::from(y), c);
                }
            }
        }
        if let Some(label) = opts.layout.views()[k].label() {
            let s = colormap::font_scale(opts.height);
            font::draw_text(&mut img, i64::from(x0) + 3 * s, 3 * s, label, s, ink);
        }
    }
    if let (Some(x), Some(scale)) = (framing.legend_x, &opts.scale) {
        colormap::draw_legend(&mut img, x, scale, ink);
    }
    Ok(img)
}

/// A mesh's normals for shading.
struct Normals {
    face: Vec<Vec3>,
    vertex: Option<Vec<Vec3>>,
}

impl Normals {
    fn of(mesh: &TriMesh, shading: Shading) -> Normals {
        Normals {
            face: shade::face_normals(mesh),
            vertex: (shading == Shading::Smooth).then(|| shade::vertex_normals(mesh)),
        }
    }
}

/// One panel's pixels (`None`: background), row-major.
fn draw_panel(
    items: &[Item],
    normals: &[Normals],
    cam: &Camera,
    opts: &RenderOptions,
) -> Vec<Option<Rgb>> {
    let mut tris = Vec::new();
    let mut starts = vec![0usize];
    for it in items {
        let screen: Vec<[f64; 3]> = it
            .mesh
            .positions
            .iter()
            .map(|p| {
                let [x, y, z] = cam.project(p);
                [x, y, z - it.lift]
            })
            .collect();
        tris.extend(it.mesh.faces.iter().map(|f| f.map(|v| screen[v as usize])));
        starts.push(tris.len());
    }
    let (w, h) = (cam.size[0] as usize, cam.size[1] as usize);
    let buf = raster::rasterise(&tris, w, h);
    let light = shade::light(&cam.right, &cam.up, &cam.forward);
    shade_pixels(&buf, w, |frag, x, y| {
        let t = frag.triangle as usize;
        let i = starts.partition_point(|&s| s <= t) - 1;
        let bary = raster::barycentric(&tris[t], x, y);
        shade_fragment(
            &items[i],
            &normals[i],
            t - starts[i],
            &bary,
            cam,
            &light,
            opts,
        )
    })
}

/// The picture of `buf` (`w` pixels a row): `shade(fragment, x, y)` at each covered pixel,
/// row by row in parallel.
fn shade_pixels<F>(buf: &[raster::Fragment], w: usize, shade: F) -> Vec<Option<Rgb>>
where
    F: Fn(&raster::Fragment, usize, usize) -> Rgb + Sync,
{
    let mut out = vec![None; buf.len()];
    out.par_chunks_mut(w)
        .zip(buf.par_chunks(w))
        .enumerate()
        .for_each(|(y, (row, frags))| {
            for (x, (px, frag)) in row.iter_mut().zip(frags).enumerate() {
                if frag.is_covered() {
                    *px = Some(shade(frag, x, y));
                }
            }
        });
    out
}

/// The colour of a fragment of face `f` of `item`.
fn shade_fragment(
    item: &Item,
    normals: &Normals,
    f: usize,
    bary: &[f64; 3],
    cam: &Camera,
    light: &Vec3,
    opts: &RenderOptions,
) -> Rgb {
    let face = item.mesh.faces[f];
    let interp =
        |v: &dyn Fn(usize) -> f64| (0..3).map(|k| bary[k] * v(face[k] as usize)).sum::<f64>();
    let nf = normals.face[f];
    let n = match &normals.vertex {
        Some(vn) => (0..3).map(|k| vn[face[k] as usize] * bary[k]).sum(),
        None => nf,
    };
    let b = shade::brightness(&n, &nf, &cam.forward, light);
    let base = match (item.values, &opts.scale) {
        (Some(v), Some(scale)) => scale.colour(interp(&|i| v[i])),
        _ => item.colour,
    };
    base.map(|c| (f64::from(c) * b).round().clamp(0.0, 255.0) as u8)
}
