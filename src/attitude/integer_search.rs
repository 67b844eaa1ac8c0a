//! The bounded integer search of the ambiguity resolver: depth-first Schnorr–Euchner
//! enumeration of the multivariate ambiguities of `M` baselines with search-and-shrink.
//!
//! The float ambiguities of the `M` baselines have covariance `Σ_B ⊗ Q₁` (same satellites and
//! wavelength on every baseline). With `Σ_B = L_B D_B L_Bᵀ` the baselines are searched in turn,
//! baseline `i` conditioned on the integers of baselines `< i`: its conditional float is
//! `ẑ_i − Σ_{k<i} (L_B)_ik (ẑ_{k|<k} − z_k)` with covariance `D_B,i Q₁`, so one LAMBDA
//! decorrelation `Zᵀ Q₁ Z = Lᵀ D L` serves every baseline. Inside a baseline the levels run from
//! the last decorrelated index to the first (conditional variance `D_B,i D_k`).
//!
//! The cost of a full candidate is `F(z) + G(z)`: the float-ambiguity distance plus the
//! constraint term the caller computes (for the constrained search, the misfit of the
//! best rotation to the conditional baselines). At the end of each baseline the caller may
//! return a lower bound of `G` from that baseline alone (the baseline-length bound), which
//! prunes the tree early. The bound shrinks to `min(χ²₀, ratio · best, second best)`, which
//! is all the ratio test needs.

use heapless::Vec;
use nalgebra::SMatrix;

use crate::attitude::snapshot::SnapshotError;
use crate::Real;

use super::lambda::Decorrelation;

/// One integer candidate (decorrelated coordinates) and its cost.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Candidate<const M: usize, const N: usize, T> {
    pub z: [[T; N]; M],
    pub cost: T,
}

/// What the search found.
pub(crate) struct SearchOutcome<const M: usize, const N: usize, T> {
    /// The best two candidates, best first.
    pub best: Vec<Candidate<M, N, T>, 2>,
    /// The final search bound (a lower bound of the second-best cost when only one was found).
    pub bound: T,
    pub nodes: u32,
    pub evaluated: u32,
}

/// The problem: decorrelated floats of each baseline, the shared factorization, `Σ_B`'s
/// `L_B` (unit lower) and `D_B`.
pub(crate) struct IntegerSearch<'a, const M: usize, const N: usize, T> {
    pub dec: &'a Decorrelation<N, T>,
    pub zhat: [[T; N]; M],
    pub l_b: SMatrix<T, M, M>,
    pub d_b: [T; M],
    pub initial_bound: T,
    pub ratio: T,
    pub max_nodes: u32,
}

#[derive(Clone, Copy)]
struct Level<T> {
    cond: T,
    z: T,
    step: T,
    before: T,
    after: T,
}

impl<T: Real> Level<T> {
    /// A level not yet entered.
    fn blank() -> Self {
        Self {
            cond: T::zero(),
            z: T::zero(),
            step: T::one(),
            before: T::zero(),
            after: T::zero(),
        }
    }
}

impl<const M: usize, const N: usize, T: Real> IntegerSearch<'_, M, N, T> {
    /// Runs the search. `partial(i, z_i)` returns a lower bound of the constraint term from
    /// baseline `i`'s integers alone; `full(z)` returns the constraint term of a full candidate
    /// (`None` rejects it).
    pub fn run(
        &self,
        mut partial: impl FnMut(usize, &[T; N]) -> T,
        mut full: impl FnMut(&[[T; N]; M]) -> Option<T>,
    ) -> Result<SearchOutcome<M, N, T>, SearchFailure> {
        let n = self.dec.n;
        if n == 0 || n > N || M == 0 {
            return Err(SearchFailure::Input(SnapshotError::Numerical));
        }
        let mut lv = [[Level::blank(); N]; M];
        let mut zbar = [[T::zero(); N]; M];
        let mut zint = [[T::zero(); N]; M];
        // largest constraint lower bound over baselines ≤ i
        let mut lb = [T::zero(); M];
        let mut out = SearchOutcome {
            best: Vec::new(),
            bound: self.initial_bound,
            nodes: 0,
            evaluated: 0,
        };
        let total = M * n;
        let mut g = 0usize;
        self.enter(g, &mut lv, &mut zbar, &zint);
        loop {
            // (bounded by max_nodes just below)
            out.nodes = out.nodes.saturating_add(1);
            if out.nodes > self.max_nodes {
                return Err(SearchFailure::Budget);
            }
            let (i, k) = (g / n, (n - 1).saturating_sub(g % n));
            let (Some(row), Some(zrow)) = (lv.get_mut(i), zint.get_mut(i)) else {
                return Err(SearchFailure::Input(SnapshotError::Numerical));
            };
            let (Some(level), Some(zk)) = (row.get_mut(k), zrow.get_mut(k)) else {
                return Err(SearchFailure::Input(SnapshotError::Numerical));
            };
            *zk = level.z;
            // the constraint bound of the baselines before this one
            let prior = i.checked_sub(1).and_then(|p| lb.get(p)).copied();
            let prior = prior.unwrap_or(T::zero());
            let here = level.after;
            if here + prior <= out.bound {
                if k > 0 {
                    g = g.saturating_add(1);
                    self.enter(g, &mut lv, &mut zbar, &zint);
                    continue;
                }
                // baseline i complete
                let descend = if i == M - 1 {
                    self.evaluate(&zint, here, &mut full, &mut out);
                    false
                } else {
                    let bound_i = zint.get(i).map(|z| partial(i, z)).unwrap_or(T::zero());
                    let merged = if bound_i > prior { bound_i } else { prior };
                    let open = here + merged <= out.bound;
                    if let (true, Some(slot)) = (open, lb.get_mut(i)) {
                        *slot = merged;
                    }
                    open
                };
                if descend {
                    g = g.saturating_add(1);
                    self.enter(g, &mut lv, &mut zbar, &zint);
                } else {
                    self.advance(g, &mut lv);
                }
                continue;
            }
            // this level is exhausted (Schnorr–Euchner order): back up
            if g == 0 {
                break;
            }
            g -= 1;
            self.advance(g, &mut lv);
            if g >= total {
                break;
            }
        }
        Ok(out)
    }

    /// A full candidate `z` with the search cost `here`: its constraint term from `full`,
    /// then kept among the best (which shrinks the bound) when finite.
    fn evaluate(
        &self,
        z: &[[T; N]; M],
        here: T,
        full: &mut impl FnMut(&[[T; N]; M]) -> Option<T>,
        out: &mut SearchOutcome<M, N, T>,
    ) {
        // (at most one per node: bounded by max_nodes)
        out.evaluated = out.evaluated.saturating_add(1);
        if let Some(extra) = full(z) {
            let cost = here + extra;
            if cost.is_finite() {
                insert(&mut out.best, Candidate { z: *z, cost });
                out.bound = self.shrink(&out.best);
            }
        }
    }

    fn shrink(&self, best: &[Candidate<M, N, T>]) -> T {
        let mut bound = self.initial_bound;
        if let Some(first) = best.first() {
            let r = first.cost * self.ratio;
            if r < bound {
                bound = r;
            }
        }
        if let Some(second) = best.get(1) {
            if second.cost < bound {
                bound = second.cost;
            }
        }
        bound
    }

    /// Enters level `g`: conditional mean, nearest integer, first step direction, distance.
    #[allow(clippy::needless_range_loop)] // index loops mirror the equations
    fn enter(
        &self,
        g: usize,
        lv: &mut [[Level<T>; N]; M],
        zbar: &mut [[T; N]; M],
        zint: &[[T; N]; M],
    ) {
        // (the clamps and `get`s let the compiler see every index in range: no panic path)
        let n = self.dec.n.min(N);
        if n == 0 {
            return;
        }
        let (i, k) = (
            (g / n).min(M - 1),
            ((n - 1).saturating_sub(g % n)).min(N - 1),
        );
        if k == n - 1 {
            // conditional float of baseline i given the integers of baselines < i
            for c in 0..n {
                let mut v = self.zhat[i][c];
                for p in 0..i {
                    v -= self.l_b[(i, p)] * (zbar[p][c] - zint[p][c]);
                }
                zbar[i][c] = v;
            }
        }
        let before = if k == n - 1 {
            if i == 0 {
                T::zero()
            } else {
                lv[i - 1][0].after
            }
        } else {
            lv[i][(k + 1).min(N - 1)].after
        };
        // cond = ẑ'_k − Σ_{l>k} L_lk (cond_l − z_l)
        let mut cond = zbar[i][k];
        for l in (k + 1)..n {
            cond -= self.dec.l[(l, k)] * (lv[i][l].cond - lv[i][l].z);
        }
        let z = cond.round();
        let step = if cond - z >= T::zero() {
            T::one()
        } else {
            -T::one()
        };
        let var = self.d_b[i] * self.dec.d[k];
        let u = cond - z;
        lv[i][k] = Level {
            cond,
            z,
            step,
            before,
            after: before + u * u / var,
        };
    }

    /// Next integer at level `g` in Schnorr–Euchner order (z, z ± 1, z ∓ 1, z ± 2, …).
    fn advance(&self, g: usize, lv: &mut [[Level<T>; N]; M]) {
        let n = self.dec.n.min(N);
        if n == 0 {
            return;
        }
        let (i, k) = (
            (g / n).min(M - 1),
            ((n - 1).saturating_sub(g % n)).min(N - 1),
        );
        let var = self.d_b[i] * self.dec.d[k];
        let level = &mut lv[i][k];
        level.z += level.step;
        let sign = if level.step > T::zero() {
            T::one()
        } else {
            -T::one()
        };
        level.step = -level.step - sign;
        let u = level.cond - level.z;
        level.after = level.before + u * u / var;
    }
}

/// Why the search stopped without an answer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum SearchFailure {
    Budget,
    Input(SnapshotError),
}

fn insert<const M: usize, const N: usize, T: Real>(
    best: &mut Vec<Candidate<M, N, T>, 2>,
    c: Candidate<M, N, T>,
) {
    // (`position` keeps an overflow check on its counter; the range's index does not)
    let position = (0..best.len())
        .zip(best.iter())
        .find(|(_, b)| c.cost < b.cost)
        .map(|(i, _)| i);
    // behind the kept ones: appended while there is room, else no rival at all
    let Some(p) = position.or((!best.is_full()).then_some(best.len())) else {
        return;
    };
    if best.is_full() {
        best.pop();
    }
    // a slot is free and `p ≤ len`: the insertion cannot fail (the `min` shows the
    // compiler the bound, which it cannot follow through the search above)
    let _ = best.insert(p.min(best.len()), c);
}
