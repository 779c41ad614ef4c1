//! Deterministic parallel loops: work is cut into fixed chunks whatever the thread count, and
//! reductions add per-chunk partial sums in chunk order, so every result is the same for any
//! `--jobs`.

use rayon::prelude::*;

/// Particles from which the per-step loops run in parallel (below, dispatch costs more than it
/// saves). Either way each particle computes the same numbers.
pub const PARALLEL_MIN: usize = 3000;

/// Items from which loops with a few operations per item (a projection, a dot product) run
/// in parallel. Measured on this project's 2-core machine (`drapekit bench speed`, 4,221
/// particles, projective dynamics): with the general threshold two threads took 3.3 s against
/// one thread's 2.2 s, waking the other thread costing more than its share of the work.
pub const LIGHT_PARALLEL_MIN: usize = 32_768;

/// Whether a loop of light work (see [`LIGHT_PARALLEL_MIN`]) over `n` items runs in parallel.
#[inline]
pub fn parallel_light(n: usize) -> bool {
    n >= LIGHT_PARALLEL_MIN && rayon::current_num_threads() > 1
}

/// Items per chunk of a reduction.
pub const REDUCE_CHUNK: usize = 1024;

/// Whether a loop over `n` items runs in parallel.
#[inline]
pub fn parallel(n: usize) -> bool {
    n >= PARALLEL_MIN && rayon::current_num_threads() > 1
}

/// Runs `body(first, a, b, c)` over fixed chunks of `chunk` items of three parallel arrays (of
/// length `n`), in parallel for large `n`.
pub fn for_chunks3<A: Send, B: Send, C: Send, F>(
    chunk: usize,
    n: usize,
    a: &mut [A],
    b: &mut [B],
    c: &mut [C],
    body: F,
) where
    F: Fn(usize, &mut [A], &mut [B], &mut [C]) + Sync,
{
    if parallel(n) {
        a.par_chunks_mut(chunk)
            .zip(b.par_chunks_mut(chunk))
            .zip(c.par_chunks_mut(chunk))
            .enumerate()
            .for_each(|(k, ((a, b), c))| body(k * chunk, a, b, c));
    } else {
        for (k, ((a, b), c)) in a
            .chunks_mut(chunk)
            .zip(b.chunks_mut(chunk))
            .zip(c.chunks_mut(chunk))
            .enumerate()
        {
            body(k * chunk, a, b, c);
        }
    }
}

/// Runs `body(first, a)` over fixed chunks of `chunk` items, in parallel for large arrays.
pub fn for_chunks<A: Send, F>(chunk: usize, a: &mut [A], body: F)
where
    F: Fn(usize, &mut [A]) + Sync,
{
    if parallel(a.len()) {
        a.par_chunks_mut(chunk)
            .enumerate()
            .for_each(|(k, a)| body(k * chunk, a));
    } else {
        for (k, a) in a.chunks_mut(chunk).enumerate() {
            body(k * chunk, a);
        }
    }
}

/// Runs `body(i, &mut a[i])` for every item, in parallel when `parallel` (the caller decides
/// from the work behind the items, e.g. `parallel(particles)` for per-chunk buffers).
pub fn for_each_mut<A: Send, F>(a: &mut [A], parallel: bool, body: F)
where
    F: Fn(usize, &mut A) + Sync,
{
    if parallel && rayon::current_num_threads() > 1 {
        a.par_iter_mut().enumerate().for_each(|(i, x)| body(i, x));
    } else {
        a.iter_mut().enumerate().for_each(|(i, x)| body(i, x));
    }
}

/// `sum_i f(i)` over `0..n`, added chunk by chunk in order (the same bits for any thread count).
pub fn sum<F>(n: usize, f: F) -> f64
where
    F: Fn(usize) -> f64 + Sync,
{
    let chunks = n.div_ceil(REDUCE_CHUNK);
    let part = |c: usize| {
        (c * REDUCE_CHUNK..((c + 1) * REDUCE_CHUNK).min(n))
            .map(&f)
            .sum::<f64>()
    };
    let partials: Vec<f64> = if parallel_light(n) {
        (0..chunks).into_par_iter().map(part).collect()
    } else {
        (0..chunks).map(part).collect()
    };
    partials.iter().sum()
}

/// `max_i f(i)` over `0..n` (0 when empty or all negative).
pub fn max<F>(n: usize, f: F) -> f64
where
    F: Fn(usize) -> f64 + Sync,
{
    if parallel(n) {
        (0..n).into_par_iter().map(&f).reduce(|| 0.0, f64::max)
    } else {
        (0..n).map(f).fold(0.0, f64::max)
    }
}
