//! The Newton matrix c·I − J of a second-order system solved by block elimination: a
//! system names the states whose rates depend on the other states only through few of
//! them ("positions" P, whose rates are velocities: J_PP block-diagonal in small groups)
//! in a [`Partition`]; (c·I − J) Δ = r then reduces to the Schur complement
//! S = c·I − J_VV − J_VP D⁻¹ J_PV on the remaining states V (D = c·I − J_PP), an LU of
//! |V|×|V| instead of N×N. The elimination is exact (no approximation of J); it is used
//! only where J_PP really is block-diagonal in the partition's groups.

use super::lu::{Lu, Scalar};
use nalgebra::{SMatrix, SVector};

/// The largest group of eliminated states.
pub const MAX_GROUP: usize = 4;

/// A partition of the state for the Newton solves: eliminated states in groups (J of
/// one group's rates with respect to another group's states must be zero) and the kept
/// states (see [`super::Rhs::newton_partition`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Partition<const N: usize> {
    /// Eliminated state indices, group after group.
    elim: [usize; N],
    n_elim: usize,
    /// (start, length) of each group in `elim`.
    groups: [(usize, usize); N],
    n_groups: usize,
    /// Kept state indices.
    keep: [usize; N],
    n_keep: usize,
}

impl<const N: usize> Partition<N> {
    /// The partition eliminating `groups` (each of 1 to `MAX_GROUP` = 4 distinct state
    /// indices below N) and keeping the other states; `None` if the groups are not so, or
    /// if they leave nothing to keep.
    pub fn new(groups: &[&[usize]]) -> Option<Self> {
        let mut p = Partition { elim: [0; N], n_elim: 0, groups: [(0, 0); N], n_groups: 0, keep: [0; N], n_keep: 0 };
        let mut used = [false; N];
        for g in groups {
            if g.is_empty() || g.len() > MAX_GROUP {
                return None;
            }
            p.groups[p.n_groups] = (p.n_elim, g.len());
            p.n_groups += 1;
            for &i in *g {
                if i >= N || used[i] {
                    return None;
                }
                used[i] = true;
                p.elim[p.n_elim] = i;
                p.n_elim += 1;
            }
        }
        for (i, u) in used.iter().enumerate() {
            if !u {
                p.keep[p.n_keep] = i;
                p.n_keep += 1;
            }
        }
        (p.n_keep > 0).then_some(p)
    }

    /// The group (0..n_groups) of each eliminated position.
    fn group_of(&self) -> [usize; N] {
        let mut g = [0; N];
        for (k, &(s, l)) in self.groups[..self.n_groups].iter().enumerate() {
            g[s..s + l].fill(k);
        }
        g
    }

    /// Is J's rates-of-P block zero between different groups?
    pub fn fits(&self, j: &SMatrix<f64, N, N>) -> bool {
        let g = self.group_of();
        for a in 0..self.n_elim {
            for b in 0..self.n_elim {
                if g[a] != g[b] && j[(self.elim[a], self.elim[b])] != 0.0 {
                    return false;
                }
            }
        }
        true
    }
}

/// c·I − J factored by block elimination over a [`Partition`], in place (its storage is
/// reused from one factorisation to the next: no large copies).
#[derive(Debug, Clone)]
pub struct ReducedLu<T: Scalar, const N: usize> {
    part: Partition<N>,
    /// Row a of D⁻¹ restricted to a's group (columns 0..group length).
    dinv: SMatrix<T, N, MAX_GROUP>,
    /// X = D⁻¹ J_PV (eliminated × kept positions).
    x: SMatrix<T, N, N>,
    /// J_VP (kept × eliminated positions).
    jvp: SMatrix<f64, N, N>,
    /// LU (partial pivoting) of S in its leading n_keep × n_keep block.
    s: SMatrix<T, N, N>,
    piv: [usize; N],
}

impl<T: Scalar, const N: usize> ReducedLu<T, N> {
    /// The partition.
    pub fn partition(&self) -> &Partition<N> {
        &self.part
    }

    /// Storage for the factorisations over `part`.
    pub fn new(part: Partition<N>) -> Self {
        ReducedLu {
            part,
            dinv: SMatrix::zeros(),
            x: SMatrix::zeros(),
            jvp: SMatrix::zeros(),
            s: SMatrix::zeros(),
            piv: [0; N],
        }
    }

    /// Factor c·I − `j`; false if D or S is singular.
    pub fn factor(&mut self, j: &SMatrix<f64, N, N>, c: T) -> bool {
        let p = self.part;
        let (ne, nk) = (p.n_elim, p.n_keep);
        for &(s, l) in &p.groups[..p.n_groups] {
            if l == 1 {
                let d = c - T::from_real(j[(p.elim[s], p.elim[s])]);
                self.dinv[(s, 0)] = T::one() / d;
                continue;
            }
            // the group's block, padded with the identity to 4×4
            let mut d = SMatrix::<T, MAX_GROUP, MAX_GROUP>::identity();
            for a in 0..l {
                for b in 0..l {
                    let diag = if a == b { c } else { T::zero() };
                    d[(a, b)] = diag - T::from_real(j[(p.elim[s + a], p.elim[s + b])]);
                }
            }
            let Some(lu) = Lu::factor(d) else { return false };
            for b in 0..l {
                let col = lu.solve(&SVector::<T, MAX_GROUP>::from_fn(|i, _| if i == b { T::one() } else { T::zero() }));
                for a in 0..l {
                    self.dinv[(s + a, b)] = col[a];
                }
            }
        }
        for &(s, l) in &p.groups[..p.n_groups] {
            for k in 0..nk {
                let col = p.keep[k];
                let zero = (0..l).all(|b| j[(p.elim[s + b], col)] == 0.0);
                for a in 0..l {
                    let mut v = T::zero();
                    if !zero {
                        for b in 0..l {
                            v += self.dinv[(s + a, b)] * T::from_real(j[(p.elim[s + b], col)]);
                        }
                    }
                    self.x[(s + a, k)] = v;
                }
            }
        }
        for r in 0..nk {
            for e in 0..ne {
                self.jvp[(r, e)] = j[(p.keep[r], p.elim[e])];
            }
            for k in 0..nk {
                let diag = if r == k { c } else { T::zero() };
                self.s[(r, k)] = diag - T::from_real(j[(p.keep[r], p.keep[k])]);
            }
        }
        // S −= J_VP X, skipping the zeros of X
        for e in 0..ne {
            for k in 0..nk {
                let xe = self.x[(e, k)];
                if xe == T::zero() {
                    continue;
                }
                for r in 0..nk {
                    self.s[(r, k)] -= T::from_real(self.jvp[(r, e)]) * xe;
                }
            }
        }
        self.factor_s(nk)
    }

    /// LU with partial pivoting of the leading m×m block of `s`, in place.
    fn factor_s(&mut self, m: usize) -> bool {
        let a = &mut self.s;
        for k in 0..m {
            let mut p = k;
            let mut mx = a[(k, k)].norm1();
            for i in k + 1..m {
                let v = a[(i, k)].norm1();
                if v > mx {
                    mx = v;
                    p = i;
                }
            }
            if !(mx > 0.0) || !mx.is_finite() {
                return false;
            }
            self.piv[k] = p;
            if p != k {
                a.swap_rows(p, k);
            }
            let d = T::one() / a[(k, k)];
            for i in k + 1..m {
                let l = a[(i, k)] * d;
                a[(i, k)] = l;
                if l == T::zero() {
                    continue;
                }
                for jj in k + 1..m {
                    let akj = a[(k, jj)];
                    a[(i, jj)] -= l * akj;
                }
            }
        }
        true
    }

    /// Solve (c·I − J) Δ = r.
    pub fn solve(&self, r: &SVector<T, N>) -> SVector<T, N> {
        let p = &self.part;
        let (ne, nk) = (p.n_elim, p.n_keep);
        // r_P' = D⁻¹ r_P
        let mut rp = SVector::<T, N>::zeros();
        for &(s, l) in &p.groups[..p.n_groups] {
            for a in 0..l {
                let mut v = T::zero();
                for b in 0..l {
                    v += self.dinv[(s + a, b)] * r[p.elim[s + b]];
                }
                rp[s + a] = v;
            }
        }
        // S Δ_V = r_V + J_VP r_P'
        let mut x = SVector::<T, N>::zeros();
        for k in 0..nk {
            let mut v = r[p.keep[k]];
            for e in 0..ne {
                v += T::from_real(self.jvp[(k, e)]) * rp[e];
            }
            x[k] = v;
        }
        for k in 0..nk {
            x.swap_rows(k, self.piv[k]);
        }
        for i in 0..nk {
            let mut s = x[i];
            for jj in 0..i {
                s -= self.s[(i, jj)] * x[jj];
            }
            x[i] = s;
        }
        for i in (0..nk).rev() {
            let mut s = x[i];
            for jj in i + 1..nk {
                s -= self.s[(i, jj)] * x[jj];
            }
            x[i] = s / self.s[(i, i)];
        }
        // Δ_P = r_P' + X Δ_V
        let mut out = SVector::<T, N>::zeros();
        for k in 0..nk {
            out[p.keep[k]] = x[k];
        }
        for e in 0..ne {
            let mut v = rp[e];
            for k in 0..nk {
                v += self.x[(e, k)] * x[k];
            }
            out[p.elim[e]] = v;
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Complex;
    use rand::{Rng, SeedableRng};

    /// On a random Jacobian of a second-order shape (positions' rates: velocities, one
    /// 3-group with its own block), the reduced solve equals the dense LU solve, real and
    /// complex; a Jacobian that couples two groups does not fit.
    #[test]
    fn reduced_solve_equals_dense() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        const N: usize = 9;
        let part = Partition::<N>::new(&[&[0], &[1], &[5, 6, 7]]).unwrap();
        for _ in 0..20 {
            let mut j = SMatrix::<f64, N, N>::from_fn(|_, _| rng.random_range(-1e3..1e3));
            for p in [0, 1, 5, 6, 7] {
                for c in [0, 1, 5, 6, 7] {
                    let same = (p < 2 && p == c) || (p >= 5 && c >= 5);
                    if !same {
                        j[(p, c)] = 0.0;
                    }
                }
            }
            j[(0, 3)] = 1.0;
            assert!(part.fits(&j));
            let b = SVector::<f64, N>::from_fn(|_, _| rng.random_range(-1.0..1.0));
            let c = rng.random_range(10.0..1e4);
            let dense = Lu::factor(SMatrix::<f64, N, N>::from_diagonal_element(c) - j).unwrap().solve(&b);
            let mut lu = ReducedLu::new(part);
            assert!(lu.factor(&j, c));
            let red = lu.solve(&b);
            assert!((dense - red).norm() <= 1e-12 * dense.norm(), "{dense} {red}");
            let cc = Complex::new(c, 0.7 * c);
            let jc = j.map(|v| Complex::new(v, 0.0));
            let bc = b.map(|v| Complex::new(v, -v));
            let dense = Lu::factor(SMatrix::<Complex<f64>, N, N>::from_diagonal_element(cc) - jc).unwrap().solve(&bc);
            let mut luc = ReducedLu::new(part);
            assert!(luc.factor(&j, cc));
            let red = luc.solve(&bc);
            assert!((dense - red).norm() <= 1e-12 * dense.norm());
            j[(1, 5)] = 1.0;
            assert!(!part.fits(&j));
        }
        assert!(Partition::<N>::new(&[&[0], &[0]]).is_none());
        assert!(Partition::<N>::new(&[&[0, 1, 2, 3, 4]]).is_none());
        assert!(Partition::<3>::new(&[&[0, 1, 2]]).is_none());
    }
}
