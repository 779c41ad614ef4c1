//! Perturbed starts: how much of a drape's outcome is chance.
//!
//! Sewing and draping a garment is chaotic: folds form, contacts switch on and off, and a
//! difference far below anything a pattern maker could measure grows into a different drape.
//! [`perturb`] moves every coordinate of every particle by a uniform offset in
//! `[-amplitude, amplitude]` (by default [`PERTURB_M`], a tenth of a micron) drawn from the
//! counter-based hash `mix(seed + mix(3 i + k))` (`math::mix`, SplitMix64) of the seed, the
//! particle `i` and the axis `k`: the same offsets on every machine and for any `--jobs`.
//! Runs with a few seeds give the spread of a garment's measures; a change to the simulator is
//! an improvement only if it moves them beyond that spread (README, `bench garment
//! --seeds`).
//!
//! ```
//! use drapekit::garment::perturb::perturb;
//! use drapekit::math::Point3;
//! let mut x = vec![Point3::new(0.0, 0.0, 1.0); 4];
//! perturb(&mut x, 7, 1e-7);
//! assert!(x.iter().all(|p| (p - Point3::new(0.0, 0.0, 1.0)).amax() <= 1e-7));
//! assert!(x[0] != x[1]);
//! ```

use crate::math::{mix, Point3};

/// The default perturbation of each coordinate, m: a tenth of a micron (a ten-thousandth of
/// the 1 mm a seam may stay open).
pub const PERTURB_M: f64 = 1e-7;

/// The offset in `[-1, 1]` of coordinate `k` of particle `i` under `seed`.
pub fn offset(seed: u64, i: usize, k: usize) -> f64 {
    let h = mix(seed.wrapping_add(mix(3 * i as u64 + k as u64)));
    // The top 53 bits as a fraction in [0, 1), then to [-1, 1).
    (h >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
}

/// Moves each coordinate of each point of `x` by `amplitude` (m) times its [`offset`].
pub fn perturb(x: &mut [Point3], seed: u64, amplitude: f64) {
    for (i, p) in x.iter_mut().enumerate() {
        for k in 0..3 {
            p[k] += amplitude * offset(seed, i, k);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offsets_are_uniform_in_the_unit_range_repeatable_and_seeded() {
        let all = |seed| -> Vec<f64> {
            (0..1000)
                .flat_map(|i| (0..3).map(move |k| offset(seed, i, k)))
                .collect()
        };
        let (a, b) = (all(1), all(2));
        assert_eq!(a, all(1));
        assert!(a.iter().all(|u| (-1.0..1.0).contains(u)));
        // Uniform on [-1, 1): mean 0 and mean |u| 1/2 (3,000 draws: standard errors 0.011 and
        // 0.005), and a different seed draws differently.
        let mean = a.iter().sum::<f64>() / 3000.0;
        let abs = a.iter().map(|u| u.abs()).sum::<f64>() / 3000.0;
        assert!(
            mean.abs() < 0.05 && (abs - 0.5).abs() < 0.025,
            "{mean} {abs}"
        );
        assert_eq!(a.iter().zip(&b).filter(|(u, v)| u == v).count(), 0);
        // Coordinates and particles draw apart.
        assert!(offset(1, 0, 0) != offset(1, 0, 1) && offset(1, 0, 0) != offset(1, 1, 0));
    }

    #[test]
    fn every_coordinate_moves_by_at_most_the_amplitude() {
        let start: Vec<Point3> = (0..100).map(|i| Point3::new(i as f64, 1.0, -2.0)).collect();
        let mut x = start.clone();
        perturb(&mut x, 5, 1e-7);
        for (p, q) in x.iter().zip(&start) {
            let d = p - q;
            assert!(d.amax() <= 1e-7 * (1.0 + 1e-6), "{d}");
            assert!(d.iter().all(|c| *c != 0.0), "{d}");
        }
    }
}
