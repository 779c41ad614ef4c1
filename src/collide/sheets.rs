//! Test and benchmark sheets: a particle grid, two grids joined, and two dense scenes for
//! cloth-against-cloth contact (a sheet crumpled in five layers, a sheet wrapped round a
//! cylinder and overlapping itself). Fixed seeds: the same sheet every time.

use crate::math::{Point3, SplitMix};

/// A grid of `nu x nv` particles at `f(i, j)`, each cell split along its `(i, j)-(i+1, j+1)`
/// diagonal, particles numbered from `first`.
pub fn grid(
    nu: usize,
    nv: usize,
    first: u32,
    f: impl Fn(usize, usize) -> Point3,
) -> (Vec<Point3>, Vec<[u32; 3]>) {
    let mut x = Vec::with_capacity(nu * nv);
    for i in 0..nu {
        for j in 0..nv {
            x.push(f(i, j));
        }
    }
    let id = |i: usize, j: usize| first + (i * nv + j) as u32;
    let mut t = Vec::new();
    for i in 0..nu - 1 {
        for j in 0..nv - 1 {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            t.push([a, b, c]);
            t.push([c, d, a]);
        }
    }
    (x, t)
}

/// Two meshes as one cloth.
pub fn join(
    a: (Vec<Point3>, Vec<[u32; 3]>),
    b: (Vec<Point3>, Vec<[u32; 3]>),
) -> (Vec<Point3>, Vec<[u32; 3]>) {
    let off = a.0.len() as u32;
    let mut x = a.0;
    x.extend(b.0);
    let mut t = a.1;
    t.extend(b.1.iter().map(|t| t.map(|v| v + off)));
    (x, t)
}

/// A `k x k` sheet of edge `size` crumpled at random (fixed seed): folded in five like an
/// accordion with `gap` between the layers, waved (every layer alike, so they stay apart),
/// jittered (across by a third of an edge, up and down by a quarter of the gap).
pub fn crumpled(k: usize, size: f64, seed: u64, gap: f64) -> (Vec<Point3>, Vec<[u32; 3]>) {
    let mut rng = SplitMix(seed);
    let (a, b, ph) = (rng.next_f64(), rng.next_f64(), 6.0 * rng.next_f64());
    let jitter: Vec<f64> = (0..3 * k * k).map(|_| rng.next_f64() - 0.5).collect();
    let layers = 5.0;
    let e = size / (k - 1) as f64;
    grid(k, k, 0, |i, j| {
        let (u, v) = (i as f64 / (k - 1) as f64, j as f64 / (k - 1) as f64);
        let w = u * layers;
        let layer = w.floor().min(layers - 1.0);
        let f = w - layer;
        let along = if layer as i64 % 2 == 0 { f } else { 1.0 - f };
        let r = 3 * (i * k + j);
        Point3::new(
            size / layers * along + 0.3 * e * jitter[r],
            size * v + 0.3 * e * jitter[r + 1],
            layer * gap
                + 0.01 * size * ((3.0 + a) * along + ph).sin() * ((5.0 + b) * v).cos()
                + 0.5 * gap * jitter[r + 2],
        )
    })
}

/// A `k x k` sheet of edge `size` wrapped round a vertical cylinder 1.1 times, the overlap
/// `gap` outside, jittered like [`crumpled`].
pub fn wrapped(k: usize, size: f64, seed: u64, gap: f64) -> (Vec<Point3>, Vec<[u32; 3]>) {
    let mut rng = SplitMix(seed);
    let jitter: Vec<f64> = (0..3 * k * k).map(|_| rng.next_f64() - 0.5).collect();
    let r = size / (1.1 * std::f64::consts::TAU);
    let e = size / (k - 1) as f64;
    grid(k, k, 0, |i, j| {
        let (u, v) = (i as f64 / (k - 1) as f64, j as f64 / (k - 1) as f64);
        let turn = u * 1.1;
        // Out by `gap` over the last tenth (where it overlaps the first).
        let rr = r + gap * ((turn - 0.95) / 0.05).clamp(0.0, 1.0);
        let a = turn * std::f64::consts::TAU;
        let q = 3 * (i * k + j);
        Point3::new(
            rr * a.cos() + 0.5 * gap * jitter[q],
            rr * a.sin() + 0.5 * gap * jitter[q + 1],
            size * v + 0.3 * e * jitter[q + 2],
        )
    })
}
