//! The cloth model: everything that never changes during a run (masses, springs, rest lengths,
//! pins, triangles, per-particle fabric values), as flat arrays.

use super::elements::{bend, Spring, SpringKind};
use super::fabric::Fabric;
use super::pattern::Piece;
use crate::math::{Point2, Point3, Vec3};
use serde::Serialize;

/// One piece's place in the model.
#[derive(Debug, Clone, Serialize)]
pub struct PieceRange {
    /// Name.
    pub name: String,
    /// First particle.
    pub first: usize,
    /// Particles.
    pub count: usize,
    /// First triangle.
    pub first_triangle: usize,
    /// Triangles.
    pub triangles: usize,
    /// Flat area, m^2.
    pub area: f64,
}

/// What never changes.
#[derive(Debug, Clone)]
pub struct ClothModel {
    /// Particle masses, kg.
    pub mass: Vec<f64>,
    /// 1 / mass, 0 for pinned particles.
    pub inv_mass: Vec<f64>,
    /// Air damping rate per particle, 1/s.
    pub damping: Vec<f64>,
    /// Collision thickness per particle, m.
    pub thickness: Vec<f64>,
    /// Friction per particle (against objects without their own).
    pub friction: Vec<f64>,
    /// Springs.
    pub springs: Vec<Spring>,
    /// Springs of each particle: `adj_start[i]..adj_start[i+1]` indexes `adj` (other end, spring).
    pub adj_start: Vec<u32>,
    /// (other particle, spring index).
    pub adj: Vec<(u32, u32)>,
    /// Bending elements: `bend_start[e]..bend_start[e+1]` indexes `bend_nodes` and
    /// `bend_weights` of element `e`; its energy is `bend_c[e] |sum w x|^2 / 2`.
    pub bend_start: Vec<u32>,
    /// Particles of the bending elements.
    pub bend_nodes: Vec<u32>,
    /// Their weights.
    pub bend_weights: Vec<f64>,
    /// Constants of the bending elements, N/m.
    pub bend_c: Vec<f64>,
    /// Bending elements of each particle: `bend_adj_start[i]..bend_adj_start[i+1]` indexes
    /// `bend_adj` (element, the particle's weight in it).
    pub bend_adj_start: Vec<u32>,
    /// (element, weight).
    pub bend_adj: Vec<(u32, f64)>,
    /// Triangles of all pieces (for output, strain, areas).
    pub triangles: Vec<[u32; 3]>,
    /// Each particle's place in its flat pattern piece, m (the rest geometry: triangle edges
    /// are at rest at these lengths). Written as `vt` in the drape and garment OBJ files.
    pub rest: Vec<Point2>,
    /// The pieces.
    pub pieces: Vec<PieceRange>,
    /// Gravity, m/s^2.
    pub gravity: Vec3,
    /// Extra force per particle, N, held constant through a step (empty: none). Sewing pulls
    /// seam sides with it (`garment::drape`).
    pub external: Vec<Vec3>,
}

impl ClothModel {
    /// Assembles pieces, each with its fabric and its 3D placement, into one model. Returns the
    /// model and the initial positions.
    pub fn assemble(
        pieces: &[(String, Piece, Fabric, Vec<Point3>)],
        gravity: Vec3,
    ) -> (ClothModel, Vec<Point3>) {
        let mut m = ClothModel {
            mass: Vec::new(),
            inv_mass: Vec::new(),
            damping: Vec::new(),
            thickness: Vec::new(),
            friction: Vec::new(),
            springs: Vec::new(),
            adj_start: Vec::new(),
            adj: Vec::new(),
            bend_start: vec![0],
            bend_nodes: Vec::new(),
            bend_weights: Vec::new(),
            bend_c: Vec::new(),
            bend_adj_start: Vec::new(),
            bend_adj: Vec::new(),
            triangles: Vec::new(),
            rest: Vec::new(),
            pieces: Vec::new(),
            gravity,
            external: Vec::new(),
        };
        let mut x = Vec::new();
        for (name, p, fabric, placed) in pieces {
            let off = m.mass.len() as u32;
            m.pieces.push(PieceRange {
                name: name.clone(),
                first: off as usize,
                count: p.flat.len(),
                first_triangle: m.triangles.len(),
                triangles: p.triangles.len(),
                area: p.area,
            });
            let first = m.mass.len();
            m.mass.extend_from_slice(&p.mass);
            m.inv_mass.extend(p.mass.iter().map(|&w| 1.0 / w));
            for &pin in &p.pinned {
                m.inv_mass[first + pin as usize] = 0.0;
            }
            m.damping
                .extend(std::iter::repeat_n(fabric.damping, p.flat.len()));
            m.thickness
                .extend(std::iter::repeat_n(fabric.thickness, p.flat.len()));
            m.friction
                .extend(std::iter::repeat_n(fabric.friction, p.flat.len()));
            m.springs.extend(p.springs.iter().map(|s| Spring {
                a: s.a + off,
                b: s.b + off,
                ..*s
            }));
            for e in &p.bends {
                m.bend_nodes.extend(e.nodes.iter().map(|v| v + off));
                m.bend_weights.extend_from_slice(&e.weights);
                m.bend_c.push(e.c);
                m.bend_start.push(m.bend_nodes.len() as u32);
            }
            m.triangles
                .extend(p.triangles.iter().map(|t| t.map(|v| v + off)));
            m.rest.extend_from_slice(&p.flat);
            x.extend_from_slice(placed);
        }
        m.index_springs();
        m.index_bends();
        (m, x)
    }

    /// Adds bending elements (across seams, say) over existing particles.
    pub fn add_bends(&mut self, bends: &[super::elements::Bend]) {
        for e in bends {
            self.bend_nodes.extend_from_slice(&e.nodes);
            self.bend_weights.extend_from_slice(&e.weights);
            self.bend_c.push(e.c);
            self.bend_start.push(self.bend_nodes.len() as u32);
        }
        self.index_bends();
    }

    /// Adds springs (seams, say) between existing particles.
    pub fn add_springs(&mut self, springs: &[Spring]) {
        self.springs.extend_from_slice(springs);
        self.index_springs();
    }

    /// Rebuilds `adj_start` and `adj` from the springs.
    fn index_springs(&mut self) {
        let n = self.mass.len();
        let mut count = vec![0u32; n + 1];
        for s in &self.springs {
            count[s.a as usize + 1] += 1;
            count[s.b as usize + 1] += 1;
        }
        for i in 0..n {
            count[i + 1] += count[i];
        }
        let mut fill = count.clone();
        self.adj = vec![(0, 0); count[n] as usize];
        for (si, s) in self.springs.iter().enumerate() {
            for (p, q) in [(s.a, s.b), (s.b, s.a)] {
                self.adj[fill[p as usize] as usize] = (q, si as u32);
                fill[p as usize] += 1;
            }
        }
        self.adj_start = count;
    }

    /// Rebuilds `bend_adj_start` and `bend_adj` from the bending elements.
    fn index_bends(&mut self) {
        let n = self.mass.len();
        let mut count = vec![0u32; n + 1];
        for &v in &self.bend_nodes {
            count[v as usize + 1] += 1;
        }
        for i in 0..n {
            count[i + 1] += count[i];
        }
        let mut fill = count.clone();
        self.bend_adj = vec![(0, 0.0); count[n] as usize];
        for e in 0..self.bend_c.len() {
            for k in self.bend_start[e] as usize..self.bend_start[e + 1] as usize {
                let v = self.bend_nodes[k] as usize;
                self.bend_adj[fill[v] as usize] = (e as u32, self.bend_weights[k]);
                fill[v] += 1;
            }
        }
        self.bend_adj_start = count;
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.mass.len()
    }

    /// Whether there are no particles.
    pub fn is_empty(&self) -> bool {
        self.mass.is_empty()
    }

    /// Whether particle `i` is pinned.
    #[inline]
    pub fn pinned(&self, i: usize) -> bool {
        self.inv_mass[i] == 0.0
    }

    /// The unknowns of a global solve: each particle's index among the free particles
    /// (`u32::MAX` if pinned), and the particle of each unknown.
    pub fn free_unknowns(&self) -> (Vec<u32>, Vec<u32>) {
        let mut index = vec![u32::MAX; self.len()];
        let mut particles = Vec::new();
        for (i, slot) in index.iter_mut().enumerate() {
            if !self.pinned(i) {
                *slot = particles.len() as u32;
                particles.push(i as u32);
            }
        }
        (index, particles)
    }

    /// Number of bending elements.
    pub fn bends(&self) -> usize {
        self.bend_c.len()
    }

    /// The weighted sum `sum w x` of bending element `e`.
    #[inline(always)]
    pub fn bend_vector(&self, e: usize, x: &[Point3]) -> Vec3 {
        let (a, b) = (self.bend_start[e] as usize, self.bend_start[e + 1] as usize);
        bend::vector(&self.bend_nodes[a..b], &self.bend_weights[a..b], x)
    }

    /// Springs of one kind.
    pub fn count(&self, kind: SpringKind) -> usize {
        self.springs.iter().filter(|s| s.kind == kind).count()
    }
}
