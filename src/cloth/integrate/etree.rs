//! Two independent subtrees of a supernodal factor's elimination tree, for sweeps on two
//! threads.
//!
//! Supernode `s`'s parent is the supernode of the first row below its columns; a parent comes
//! after its children (faer numbers supernodes in a postorder), so a subtree is a contiguous
//! range of supernodes and of columns. Two disjoint subtrees `A` and `B` share no column, and
//! neither writes the other's rows in either sweep: the forward sweep of a column updates only
//! rows of its ancestors, the backward sweep reads only them. What `A` and `B` both touch is
//! the rest, `T` (their common ancestors and any other supernodes): in the forward sweep each
//! adds its updates of `T`'s rows into a buffer of its own, and the buffers are added to `T`'s
//! rows in a fixed order (`A`'s, then `B`'s) before `T` is swept; in the backward sweep `T` is
//! swept first and `A` and `B` read copies of its rows. The arithmetic is the same whether the
//! two run at once or one after the other, so the solution does not depend on the thread count.
//!
//! **The split.** With `W(s)` the work of the subtree of `s` (entries of `L` it reads), the
//! candidates keep the first `k` nodes of the heaviest path from the root in `T`; the subtrees
//! hanging from them go to two threads, largest first to the less loaded one. On two threads
//! a candidate costs the larger load plus the path's own work; the cheapest is kept if it
//! saves at least [`MIN_SAVING`] of the serial work.
//!
//! ```
//! use drapekit::cloth::integrate::etree::Split;
//! // Two chains of two supernodes (0 -> 1 and 2 -> 3) under a root 4, equal work each.
//! let split = Split::find(&[1, 4, 3, 4, u32::MAX], &[1.0; 5], &[0, 1, 2, 3, 4, 5]).unwrap();
//! assert_eq!(split.parts, [vec![0..2], vec![2..4]]);
//! assert_eq!(split.top, vec![4..5]);
//! assert!((split.cost - 3.0).abs() < 1e-12);
//! ```

use std::ops::Range;

/// The least fraction of the serial work a split must save to be used.
pub const MIN_SAVING: f64 = 0.2;

/// No parent (a root of the elimination forest).
pub const NONE: u32 = u32::MAX;

/// Subtrees for two threads (`parts`: ranges of supernodes, ascending) and the rest (`top`,
/// ascending ranges), with their columns.
#[derive(Debug, Clone, PartialEq)]
pub struct Split {
    pub parts: [Vec<Range<usize>>; 2],
    pub top: Vec<Range<usize>>,
    /// The columns of each part's subtrees.
    pub part_cols: [Vec<Range<usize>>; 2],
    /// The columns of `top`, ascending, and for each column its index there (`NONE` outside).
    pub top_cols: Vec<u32>,
    pub top_pos: Vec<u32>,
    /// The work on two threads, in the units of `work`.
    pub cost: f64,
}

impl Split {
    /// The best split of the forest `parent` (per supernode; `NONE` for a root; a parent after
    /// its children) with `work` per supernode and supernode `s` holding columns
    /// `begin[s]..begin[s + 1]`; `None` if no split saves [`MIN_SAVING`] or the tree is not
    /// in postorder.
    pub fn find(parent: &[u32], work: &[f64], begin: &[usize]) -> Option<Split> {
        let ns = parent.len();
        let (mut w, mut first) = (work.to_vec(), (0..ns).collect::<Vec<_>>());
        let mut size = vec![1usize; ns];
        let mut children: Vec<Vec<usize>> = vec![Vec::new(); ns + 1];
        for s in 0..ns {
            let p = parent[s];
            if p != NONE && (p as usize) <= s {
                return None;
            }
            if p != NONE {
                let p = p as usize;
                w[p] += w[s];
                first[p] = first[p].min(first[s]);
                size[p] += size[s];
            }
            children[if p == NONE { ns } else { p as usize }].push(s);
        }
        if (0..ns).any(|s| size[s] != s + 1 - first[s]) {
            return None;
        }
        let total: f64 = work.iter().sum();
        let (bins, cost) = best_bins(&children, &w, work, total)?;
        if cost > (1.0 - MIN_SAVING) * total {
            return None;
        }
        let parts = bins.map(|b| {
            let mut r: Vec<Range<usize>> = b.iter().map(|&c| first[c]..c + 1).collect();
            r.sort_by_key(|r| r.start);
            r
        });
        Some(Split::of(parts, begin, cost))
    }

    /// The split with the parts' subtrees `parts`.
    fn of(parts: [Vec<Range<usize>>; 2], begin: &[usize], cost: f64) -> Split {
        let ns = begin.len() - 1;
        let mut in_part = vec![false; ns];
        parts
            .iter()
            .flatten()
            .for_each(|r| in_part[r.clone()].fill(true));
        let mut top: Vec<Range<usize>> = Vec::new();
        for s in (0..ns).filter(|&s| !in_part[s]) {
            match top.last_mut() {
                Some(r) if r.end == s => r.end = s + 1,
                _ => top.push(s..s + 1),
            }
        }
        let mut top_pos = vec![NONE; begin[ns]];
        let mut top_cols = Vec::new();
        for r in &top {
            for c in begin[r.start]..begin[r.end] {
                top_pos[c] = top_cols.len() as u32;
                top_cols.push(c as u32);
            }
        }
        let cols = |p: &Vec<Range<usize>>| p.iter().map(|r| begin[r.start]..begin[r.end]).collect();
        Split {
            part_cols: [cols(&parts[0]), cols(&parts[1])],
            parts,
            top,
            top_cols,
            top_pos,
            cost,
        }
    }
}

/// Down the heaviest path from the (virtual) root, the subtrees hanging from its first nodes
/// in two bins (largest first to the lighter), for the number of path nodes that costs least
/// on two threads: the bins' roots and the cost.
fn best_bins(
    children: &[Vec<usize>],
    w: &[f64],
    own: &[f64],
    total: f64,
) -> Option<([Vec<usize>; 2], f64)> {
    let mut best: Option<([Vec<usize>; 2], f64)> = None;
    let (mut v, mut path_work) = (children.len() - 1, 0.0);
    let mut hanging: Vec<usize> = Vec::new();
    loop {
        let heavy = children[v]
            .iter()
            .copied()
            .max_by(|&x, &y| w[x].total_cmp(&w[y]).then(y.cmp(&x)));
        let mut items: Vec<usize> = hanging.iter().chain(&children[v]).copied().collect();
        items.sort_by(|&x, &y| w[y].total_cmp(&w[x]).then(x.cmp(&y)));
        let mut bins: [Vec<usize>; 2] = [Vec::new(), Vec::new()];
        let mut load = [0.0; 2];
        for c in items {
            let k = usize::from(load[1] < load[0]);
            bins[k].push(c);
            load[k] += w[c];
        }
        let cost = load[0].max(load[1]) + path_work;
        debug_assert!(cost <= total * (1.0 + 1e-12));
        if !bins[1].is_empty() && best.as_ref().is_none_or(|(_, c)| cost < *c) {
            best = Some((bins, cost));
        }
        let h = heavy?;
        hanging.extend(children[v].iter().copied().filter(|&c| c != h));
        path_work += own[h];
        v = h;
        if children[v].is_empty() {
            return best;
        }
    }
}
