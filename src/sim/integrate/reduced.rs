//! The Newton matrix c·I − J of a second-order system solved by block elimination. A
//! system names in a [`Partition`] the states whose rates depend on the other states only
//! through few of them ("positions" P, whose rates are velocities: J_PP block-diagonal in
//! small groups) and the "trailing" states F on which no other rate depends (a low-pass
//! filter of an output: column F of J is zero but for its own entry). (c·I − J) Δ = r then
//! reduces to the Schur complement S = c·I − J_VV − J_VP D⁻¹ J_PV on the remaining states V
//! (D = c·I − J_PP), an LU of |V|×|V| instead of N×N; the positions follow from Δ_V and the
//! trailing states last, one division each. The elimination is exact (no approximation of
//! J); it is used only where J really has this structure ([`Partition::fits`]).
//!
//! The parts of J the elimination needs are gathered once per Jacobian
//! ([`ReducedLu::prepare`]), with the c-independent product J_VP J_PV of the one-state
//! groups whose own rate does not depend on themselves (a position whose rate is a
//! velocity: D⁻¹ = 1/c); each factorisation ([`ReducedLu::factor`], the real and the
//! complex shift of Radau IIA together) then only adds c·I, that product over c and the
//! other groups' terms, and factors S.

use super::lu::Lu;
use super::schur_lu::{ReducedScalar, SchurLu};
use nalgebra::{Complex, SMatrix, SVector};

/// The largest group of eliminated states.
pub const MAX_GROUP: usize = 4;

/// A partition of the state for the Newton solves: eliminated states in groups (J of
/// one group's rates with respect to another group's states must be zero), trailing states
/// (no other state's rate depends on them) and the kept states (see
/// [`super::Rhs::newton_partition`]).
#[derive(Debug, Clone, Copy, PartialEq)]
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
    /// Trailing state indices.
    trail: [usize; N],
    n_trail: usize,
    /// ∂f_i/∂y_i of a trailing state whose rate is linear in itself with a known
    /// coefficient (its Jacobian column needs no evaluation).
    linear: [Option<f64>; N],
}

impl<const N: usize> Partition<N> {
    /// The partition eliminating `groups` (each of 1 to `MAX_GROUP` = 4 distinct state
    /// indices below N) and keeping the other states; `None` if the groups are not so, or
    /// if they leave nothing to keep.
    pub fn new(groups: &[&[usize]]) -> Option<Self> {
        let mut p = Partition {
            elim: [0; N],
            n_elim: 0,
            groups: [(0, 0); N],
            n_groups: 0,
            keep: [0; N],
            n_keep: 0,
            trail: [0; N],
            n_trail: 0,
            linear: [None; N],
        };
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

    /// This partition with the kept states `trailing` solved last instead (states no other
    /// rate depends on, e.g. a filter of an output); `None` if one is not a kept state or
    /// if nothing would be kept.
    pub fn with_trailing(mut self, trailing: &[usize]) -> Option<Self> {
        for &t in trailing {
            let at = self.keep[..self.n_keep].iter().position(|&k| k == t)?;
            self.keep.copy_within(at + 1..self.n_keep, at);
            self.n_keep -= 1;
            self.trail[self.n_trail] = t;
            self.n_trail += 1;
        }
        (self.n_keep > 0).then_some(self)
    }

    /// This partition with trailing states (see [`Partition::with_trailing`]) whose rate
    /// depends on themselves linearly with the known coefficient ∂f_i/∂y_i (a first-order
    /// filter of an output, y_i' = (u − y_i)/T: −1/T); their Jacobian columns are then known
    /// ([`Partition::known_column`]).
    pub fn with_trailing_linear(self, trailing: &[(usize, f64)]) -> Option<Self> {
        let idx: Vec<usize> = trailing.iter().map(|t| t.0).collect();
        let mut p = self.with_trailing(&idx)?;
        for &(i, rate) in trailing {
            p.linear[i] = Some(rate);
        }
        Some(p)
    }

    /// The Jacobian column of state `j` where the partition knows it: a linear trailing
    /// state's column is zero but for its diagonal entry.
    pub fn known_column(&self, j: usize) -> Option<f64> {
        self.linear.get(j).copied().flatten()
    }

    /// The group (0..n_groups) of each eliminated position.
    fn group_of(&self) -> [usize; N] {
        let mut g = [0; N];
        for (k, &(s, l)) in self.groups[..self.n_groups].iter().enumerate() {
            g[s..s + l].fill(k);
        }
        g
    }

    /// Does `j` have the structure: J's rates-of-P block zero between different groups, and
    /// every trailing state's column zero but for its own entry?
    pub fn fits(&self, j: &SMatrix<f64, N, N>) -> bool {
        let g = self.group_of();
        for a in 0..self.n_elim {
            for b in 0..self.n_elim {
                if g[a] != g[b] && j[(self.elim[a], self.elim[b])] != 0.0 {
                    return false;
                }
            }
        }
        for &t in &self.trail[..self.n_trail] {
            if (0..N).any(|r| r != t && j[(r, t)] != 0.0) {
                return false;
            }
        }
        true
    }
}

/// The factorisation of c·I − J for one shift c (real or complex).
#[derive(Debug, Clone)]
struct Factor<T: ReducedScalar, const N: usize> {
    /// 1/c.
    inv_c: T,
    /// Row a of D⁻¹ restricted to a's group, for the general groups.
    dinv: [[T; MAX_GROUP]; N],
    /// X = D⁻¹ J_PV for the rows of the general groups (eliminated × kept).
    x: [[T; N]; N],
    /// LU of S.
    s: T::Mat<N>,
    /// 1 / (c − J_FF) of each trailing state.
    trail_div: [T; N],
    /// The general groups' own blocks J_GG are negligible against c (see
    /// [`NEGLIGIBLE`]): they are eliminated as the simple ones, D⁻¹ = I/c.
    groups_as_simple: bool,
}

/// A general group's own block J_GG is neglected in the Newton matrix where its entries
/// are at most this fraction of |c| (c = γ/h or (α + iβ)/h): D = c·I − J_GG is then I·c to
/// this relative accuracy, an approximation of the Newton matrix far smaller than that of
/// a Jacobian reused over steps (the free scene's quaternion rates: |J_GG| ≈ |ω|/2).
pub const NEGLIGIBLE: f64 = 1e-3;

impl<T: ReducedScalar, const N: usize> Factor<T, N> {
    fn new() -> Self {
        Factor {
            groups_as_simple: false,
            inv_c: T::zero(),
            dinv: [[T::zero(); MAX_GROUP]; N],
            x: [[T::zero(); N]; N],
            s: T::Mat::<N>::zeros(),
            trail_div: [T::zero(); N],
        }
    }
}

/// The parts of J the elimination needs, in the partition's compact order.
#[derive(Debug, Clone)]
struct Prepared<const N: usize> {
    /// J_VV (kept × kept).
    jvv: [[f64; N]; N],
    /// J_VP (kept × eliminated).
    jvp: [[f64; N]; N],
    /// The nonzeros of each row of J_PV (eliminated × kept): (kept index, value).
    jpv: [[(usize, f64); N]; N],
    jpv_len: [usize; N],
    /// Σ over the simple groups of J_VP[:, p] J_PV[p, :] (kept × kept).
    b: [[f64; N]; N],
    /// The compact indices of the simple groups' positions (one-state groups whose rate
    /// does not depend on themselves: D⁻¹ = 1/c).
    simple_at: [usize; N],
    n_simple: usize,
    /// The other groups: (start, length), their J_GG blocks, and the kept columns where
    /// their J_GV rows have nonzeros.
    general: [(usize, usize); N],
    n_general: usize,
    jgg: [[[f64; MAX_GROUP]; MAX_GROUP]; N],
    gcols: [[usize; N]; N],
    gcols_len: [usize; N],
    /// B plus the general groups' J_VG J_GV, and the largest |entry| of their J_GG.
    b_all: [[f64; N]; N],
    jgg_max: f64,
    /// The nonzeros of each trailing state's row off its diagonal (state index, value),
    /// and its diagonal entry.
    jf: [[(usize, f64); N]; N],
    jf_len: [usize; N],
    jff: [f64; N],
}

/// c·I − J factored by block elimination over a [`Partition`], for a real and a complex
/// shift at once (Radau IIA's γ/h and (α + iβ)/h), in place: the parts of J are gathered
/// once per Jacobian ([`ReducedLu::prepare`]) and reused by every factorisation.
#[derive(Debug, Clone)]
pub struct ReducedLu<const N: usize> {
    part: Partition<N>,
    prep: Box<Prepared<N>>,
    real: Box<Factor<f64, N>>,
    cplx: Box<Factor<Complex<f64>, N>>,
}

impl<const N: usize> ReducedLu<N> {
    /// Storage for the factorisations over `part`.
    pub fn new(part: Partition<N>) -> Self {
        ReducedLu {
            part,
            prep: Box::new(Prepared {
                jvv: [[0.0; N]; N],
                jvp: [[0.0; N]; N],
                jpv: [[(0, 0.0); N]; N],
                jpv_len: [0; N],
                b: [[0.0; N]; N],
                simple_at: [0; N],
                n_simple: 0,
                general: [(0, 0); N],
                n_general: 0,
                jgg: [[[0.0; MAX_GROUP]; MAX_GROUP]; N],
                gcols: [[0; N]; N],
                gcols_len: [0; N],
                b_all: [[0.0; N]; N],
                jgg_max: 0.0,
                jf: [[(0, 0.0); N]; N],
                jf_len: [0; N],
                jff: [0.0; N],
            }),
            real: Box::new(Factor::new()),
            cplx: Box::new(Factor::new()),
        }
    }

    /// Gather the parts of `j` (false: `j` does not fit the partition, see
    /// [`Partition::fits`]).
    #[inline(never)]
    pub fn prepare(&mut self, j: &SMatrix<f64, N, N>) -> bool {
        let p = &self.part;
        if !p.fits(j) {
            return false;
        }
        let (ne, nk) = (p.n_elim, p.n_keep);
        let pr = &mut *self.prep;
        for r in 0..nk {
            let jr = p.keep[r];
            for k in 0..nk {
                pr.jvv[r][k] = j[(jr, p.keep[k])];
            }
            for e in 0..ne {
                pr.jvp[r][e] = j[(jr, p.elim[e])];
            }
        }
        for e in 0..ne {
            let mut n = 0;
            for k in 0..nk {
                let v = j[(p.elim[e], p.keep[k])];
                if v != 0.0 {
                    pr.jpv[e][n] = (k, v);
                    n += 1;
                }
            }
            pr.jpv_len[e] = n;
        }
        for row in pr.b[..nk].iter_mut() {
            row[..nk].fill(0.0);
        }
        pr.n_simple = 0;
        pr.n_general = 0;
        pr.jgg_max = 0.0;
        for &(s, l) in &p.groups[..p.n_groups] {
            if l == 1 && j[(p.elim[s], p.elim[s])] == 0.0 {
                pr.simple_at[pr.n_simple] = s;
                pr.n_simple += 1;
                for &(k, v) in &pr.jpv[s][..pr.jpv_len[s]] {
                    for r in 0..nk {
                        pr.b[r][k] += pr.jvp[r][s] * v;
                    }
                }
                continue;
            }
            let g = pr.n_general;
            pr.general[g] = (s, l);
            pr.n_general += 1;
            let mut used = [false; N];
            for a in 0..l {
                for c in 0..l {
                    pr.jgg[g][a][c] = j[(p.elim[s + a], p.elim[s + c])];
                    pr.jgg_max = pr.jgg_max.max(pr.jgg[g][a][c].abs());
                }
                for &(k, _) in &pr.jpv[s + a][..pr.jpv_len[s + a]] {
                    used[k] = true;
                }
            }
            let mut n = 0;
            for (k, _) in used.iter().enumerate().filter(|(_, u)| **u) {
                pr.gcols[g][n] = k;
                n += 1;
            }
            pr.gcols_len[g] = n;
        }
        pr.b_all[..nk].copy_from_slice(&pr.b[..nk]);
        for &(s, l) in &pr.general[..pr.n_general] {
            for e in s..s + l {
                for &(k, v) in &pr.jpv[e][..pr.jpv_len[e]] {
                    for r in 0..nk {
                        pr.b_all[r][k] += pr.jvp[r][e] * v;
                    }
                }
            }
        }
        for (t, &ft) in p.trail[..p.n_trail].iter().enumerate() {
            let mut n = 0;
            for i in (0..N).filter(|&i| i != ft) {
                let v = j[(ft, i)];
                if v != 0.0 {
                    pr.jf[t][n] = (i, v);
                    n += 1;
                }
            }
            pr.jf_len[t] = n;
            pr.jff[t] = j[(ft, ft)];
        }
        true
    }

    /// Factor c·I − J (J as last prepared) for the real shift `c` and the complex shift
    /// `cc`; false if D or S is singular for either.
    pub fn factor(&mut self, c: f64, cc: Complex<f64>) -> bool {
        factor_one(&self.part, &self.prep, &mut self.real, c) && factor_one(&self.part, &self.prep, &mut self.cplx, cc)
    }

    /// Factor c·I − J (J as last prepared) for the complex shift `cc` only (a method with
    /// several complex shifts keeps one `ReducedLu` per shift).
    pub fn factor_complex(&mut self, cc: Complex<f64>) -> bool {
        factor_one(&self.part, &self.prep, &mut self.cplx, cc)
    }

    /// Solve (c·I − J) Δ = r for the real shift.
    pub fn solve_real(&self, r: &SVector<f64, N>) -> SVector<f64, N> {
        let x = solve_one(&self.part, &self.prep, &self.real, |i| r[i]);
        SVector::<f64, N>::from_fn(|i, _| x[i])
    }

    /// Solve (c·I − J) Δ = re + i·im for the complex shift: (Re Δ, Im Δ).
    pub fn solve_complex(&self, re: &SVector<f64, N>, im: &SVector<f64, N>) -> (SVector<f64, N>, SVector<f64, N>) {
        let x = solve_one(&self.part, &self.prep, &self.cplx, |i| Complex::new(re[i], im[i]));
        (SVector::<f64, N>::from_fn(|i, _| x[i].re), SVector::<f64, N>::from_fn(|i, _| x[i].im))
    }
}

/// Factor c·I − J over `p` with the prepared parts `pr` into `f`.
#[inline(never)]
fn factor_one<T: ReducedScalar, const N: usize>(
    p: &Partition<N>,
    pr: &Prepared<N>,
    f: &mut Factor<T, N>,
    c: T,
) -> bool {
    let nk = p.n_keep;
    f.inv_c = T::one() / c;
    let inv_c = f.inv_c;
    f.groups_as_simple = pr.n_general > 0 && pr.jgg_max <= NEGLIGIBLE * c.modulus();
    if f.groups_as_simple {
        // S = c·I − J_VV − (B + J_VG J_GV)/c
        f.s.build(c, inv_c, &pr.jvv, &pr.b_all, nk);
    } else {
        // S = c·I − J_VV − B/c − Σ_G J_VG D_G⁻¹ J_GV
        f.s.build(c, inv_c, &pr.jvv, &pr.b, nk);
        for g in 0..pr.n_general {
            if !eliminate_group(pr, f, g, c, nk) {
                return false;
            }
        }
    }
    for t in 0..p.n_trail {
        let d = c - T::from_real(pr.jff[t]);
        if !(d.norm1() > 0.0) {
            return false;
        }
        f.trail_div[t] = T::one() / d;
    }
    f.s.factor(nk)
}

/// The exact elimination of general group `g` into `f` for the shift `c`: D⁻¹, X = D⁻¹
/// J_GV and S −= J_VG X; false if D is singular.
fn eliminate_group<T: ReducedScalar, const N: usize>(
    pr: &Prepared<N>,
    f: &mut Factor<T, N>,
    g: usize,
    c: T,
    nk: usize,
) -> bool {
    let (s, l) = pr.general[g];
    // the group's block c·I − J_GG, padded with the identity to 4×4
    let mut d = SMatrix::<T, MAX_GROUP, MAX_GROUP>::identity();
    for a in 0..l {
        for b in 0..l {
            let diag = if a == b { c } else { T::zero() };
            d[(a, b)] = diag - T::from_real(pr.jgg[g][a][b]);
        }
    }
    let Some(lu) = Lu::factor(d) else { return false };
    for b in 0..l {
        let col = lu.solve(&SVector::<T, MAX_GROUP>::from_fn(|i, _| if i == b { T::one() } else { T::zero() }));
        for a in 0..l {
            f.dinv[s + a][b] = col[a];
        }
    }
    // X = D⁻¹ J_GV for the group's rows (nonzero in the group's columns only), and
    // S −= J_VG X in those columns
    let cols = &pr.gcols[g][..pr.gcols_len[g]];
    for a in 0..l {
        for &k in cols {
            f.x[s + a][k] = T::zero();
        }
        for b in 0..l {
            let dab = f.dinv[s + a][b];
            for &(k, v) in &pr.jpv[s + b][..pr.jpv_len[s + b]] {
                f.x[s + a][k] += dab.mul_real(v);
            }
        }
    }
    for r in 0..nk {
        for a in 0..l {
            let jra = pr.jvp[r][s + a];
            if jra != 0.0 {
                for &k in cols {
                    f.s.sub_scaled(r, k, f.x[s + a][k], jra);
                }
            }
        }
    }
    true
}

/// Solve (c·I − J) Δ = r with the factorisation `f`; `r(i)` reads r_i. Returns Δ.
#[inline]
fn solve_one<T: ReducedScalar, const N: usize>(
    p: &Partition<N>,
    pr: &Prepared<N>,
    f: &Factor<T, N>,
    r: impl Fn(usize) -> T,
) -> [T; N] {
    let (ne, nk) = (p.n_elim, p.n_keep);
    // r_P' = D⁻¹ r_P
    let mut rp = [T::zero(); N];
    for &e in &pr.simple_at[..pr.n_simple] {
        rp[e] = r(p.elim[e]) * f.inv_c;
    }
    for &(s, l) in &pr.general[..pr.n_general] {
        if f.groups_as_simple {
            for e in s..s + l {
                rp[e] = r(p.elim[e]) * f.inv_c;
            }
            continue;
        }
        for a in 0..l {
            let mut v = T::zero();
            for b in 0..l {
                v += f.dinv[s + a][b] * r(p.elim[s + b]);
            }
            rp[s + a] = v;
        }
    }
    // S Δ_V = r_V + J_VP r_P'
    let mut x = [T::zero(); N];
    let rp_e = &rp[..ne];
    for (k, xk) in x[..nk].iter_mut().enumerate() {
        let mut v = r(p.keep[k]);
        let jk = &pr.jvp[k][..ne];
        for e in 0..ne {
            v += rp_e[e].mul_real(jk[e]);
        }
        *xk = v;
    }
    f.s.solve(&mut x, nk);
    // Δ_P = r_P' + X Δ_V
    let mut all = [T::zero(); N];
    for k in 0..nk {
        all[p.keep[k]] = x[k];
    }
    let as_simple = |e: usize| {
        let mut acc = T::zero();
        for &(k, jv) in &pr.jpv[e][..pr.jpv_len[e]] {
            acc += x[k].mul_real(jv);
        }
        rp[e] + acc * f.inv_c
    };
    for &e in &pr.simple_at[..pr.n_simple] {
        all[p.elim[e]] = as_simple(e);
    }
    for (g, &(s, l)) in pr.general[..pr.n_general].iter().enumerate() {
        if f.groups_as_simple {
            for e in s..s + l {
                all[p.elim[e]] = as_simple(e);
            }
            continue;
        }
        for a in s..s + l {
            let mut v = rp[a];
            for &k in &pr.gcols[g][..pr.gcols_len[g]] {
                v += f.x[a][k] * x[k];
            }
            all[p.elim[a]] = v;
        }
    }
    // the trailing states: (c − J_FF) Δ_F = r_F + J_F,rest Δ_rest
    for t in 0..p.n_trail {
        let mut v = r(p.trail[t]);
        for &(i, jv) in &pr.jf[t][..pr.jf_len[t]] {
            v += all[i].mul_real(jv);
        }
        all[p.trail[t]] = v * f.trail_div[t];
    }
    all
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    const N: usize = 9;

    /// The random source (seeded) and the layout [`random_jacobian`] draws for: groups {0},
    /// {1}, {5, 6, 7} and the trailing state 8, with its reduced LU.
    fn fixture(seed: u64) -> (rand_chacha::ChaCha8Rng, Partition<N>, ReducedLu<N>) {
        let part = Partition::<N>::new(&[&[0], &[1], &[5, 6, 7]]).unwrap().with_trailing(&[8]).unwrap();
        (rand_chacha::ChaCha8Rng::seed_from_u64(seed), part, ReducedLu::new(part))
    }

    /// A random Jacobian of a second-order shape for `part`-like layouts: positions 0, 1
    /// (rates: velocities 2, 3 plus noise), a 3-group 5..8 with its own block, a trailing
    /// state 8 (depends on everything, nothing depends on it).
    fn random_jacobian(rng: &mut impl Rng) -> SMatrix<f64, 9, 9> {
        let mut j = SMatrix::<f64, 9, 9>::from_fn(|_, _| rng.random_range(-1e3..1e3));
        for p in [0, 1, 5, 6, 7] {
            for c in [0, 1, 5, 6, 7] {
                let same = (p >= 5 && c >= 5) || (p == c && rng.random_bool(0.5));
                if !same {
                    j[(p, c)] = 0.0;
                }
            }
        }
        // position 0's rate is a velocity exactly, position 1's a combination
        for c in 0..9 {
            j[(0, c)] = 0.0;
        }
        j[(0, 2)] = 1.0;
        for r in 0..8 {
            j[(r, 8)] = 0.0;
        }
        j
    }

    /// On random Jacobians of a second-order shape, the reduced solve equals the dense LU
    /// solve (nalgebra's), real and complex, to rounding; a Jacobian that couples two
    /// groups, or a state to a trailing one, does not fit.
    #[test]
    fn reduced_solve_equals_dense() {
        let (mut rng, part, mut lu) = fixture(3);
        for _ in 0..50 {
            let mut j = random_jacobian(&mut rng);
            assert!(part.fits(&j));
            assert!(lu.prepare(&j));
            let c = rng.random_range(10.0..1e4);
            let cc = Complex::new(c, rng.random_range(-1.0..1.0) * c);
            assert!(lu.factor(c, cc));
            let b = SVector::<f64, N>::from_fn(|_, _| rng.random_range(-1.0..1.0));
            let dense = (SMatrix::<f64, N, N>::from_diagonal_element(c) - j).lu().solve(&b).unwrap();
            let red = lu.solve_real(&b);
            assert!((dense - red).norm() <= 1e-12 * dense.norm(), "{dense} {red}");
            let bi = SVector::<f64, N>::from_fn(|_, _| rng.random_range(-1.0..1.0));
            let bc = b.zip_map(&bi, Complex::new);
            let jc = j.map(|v| Complex::new(v, 0.0));
            let dense = (SMatrix::<Complex<f64>, N, N>::from_diagonal_element(cc) - jc).lu().solve(&bc).unwrap();
            let (re, im) = lu.solve_complex(&b, &bi);
            let red = re.zip_map(&im, Complex::new);
            assert!((dense - red).norm() <= 1e-12 * dense.norm());
            let mut j2 = j;
            j2[(1, 5)] = 1.0;
            assert!(!part.fits(&j2) && !lu.prepare(&j2));
            j[(3, 8)] = 1.0;
            assert!(!part.fits(&j));
        }
        assert!(Partition::<N>::new(&[&[0], &[0]]).is_none());
        assert!(Partition::<N>::new(&[&[0, 1, 2, 3, 4]]).is_none());
        assert!(Partition::<3>::new(&[&[0, 1, 2]]).is_none());
        assert!(Partition::<3>::new(&[&[0]]).unwrap().with_trailing(&[0]).is_none());
        assert!(Partition::<3>::new(&[&[0]]).unwrap().with_trailing(&[1, 2]).is_none());
    }

    /// A general group whose own block is below NEGLIGIBLE·|c| is eliminated as if the
    /// block were zero: the reduced solve equals the dense solve of c·I − J with J_GG = 0
    /// (to rounding), and differs from the exact one by O(|J_GG|/|c|).
    #[test]
    fn negligible_group_block_is_dropped() {
        let (mut rng, _, mut lu) = fixture(5);
        for _ in 0..20 {
            let mut j = random_jacobian(&mut rng);
            j[(1, 1)] = 0.0;
            let c = rng.random_range(1e3..1e4);
            for a in 5..8 {
                for b in 5..8 {
                    j[(a, b)] = rng.random_range(-1.0..1.0) * 0.5 * NEGLIGIBLE * c;
                }
            }
            assert!(lu.prepare(&j));
            let cc = Complex::new(c, 0.5 * c);
            assert!(lu.factor(c, cc));
            let b = SVector::<f64, N>::from_fn(|_, _| rng.random_range(-1.0..1.0));
            let mut j0 = j;
            for a in 5..8 {
                for b in 5..8 {
                    j0[(a, b)] = 0.0;
                }
            }
            let dropped = (SMatrix::<f64, N, N>::from_diagonal_element(c) - j0).lu().solve(&b).unwrap();
            let exact = (SMatrix::<f64, N, N>::from_diagonal_element(c) - j).lu().solve(&b).unwrap();
            let red = lu.solve_real(&b);
            assert!((dropped - red).norm() <= 1e-12 * dropped.norm());
            assert!((exact - red).norm() <= 1e-2 * exact.norm());
            let jc = j0.map(|v| Complex::new(v, 0.0));
            let bc = b.map(|v| Complex::new(v, 0.0));
            let dense = (SMatrix::<Complex<f64>, N, N>::from_diagonal_element(cc) - jc).lu().solve(&bc).unwrap();
            let (re, im) = lu.solve_complex(&b, &SVector::zeros());
            assert!((dense - re.zip_map(&im, Complex::new)).norm() <= 1e-12 * dense.norm());
        }
    }
}
