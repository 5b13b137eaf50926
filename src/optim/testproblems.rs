//! Standard test problems (as defined in pymoo) with analytic Pareto fronts for IGD.

use super::{Evaluated, Infeasibility, MooProblem, Survival, Variation};
use std::f64::consts::PI;

/// The test problems of `gripopt moo-test`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TestProblem {
    /// ZDT1 (30 variables).
    Zdt1,
    /// ZDT2 (30 variables).
    Zdt2,
    /// ZDT3 (30 variables).
    Zdt3,
    /// DTLZ2 (3 objectives, 12 variables).
    Dtlz2,
    /// BNH (2 variables, 2 constraints).
    Bnh,
    /// TNK (2 variables, 2 constraints).
    Tnk,
    /// OSY (6 variables, 6 constraints).
    Osy,
    /// C2-DTLZ2 (3 objectives, 12 variables, r = 0.4).
    C2Dtlz2,
}

/// A test problem instance with its bounds.
#[derive(Debug, Clone)]
pub struct Test {
    /// Which problem.
    pub which: TestProblem,
    lo: Vec<f64>,
    hi: Vec<f64>,
}

impl TestProblem {
    /// All, in the order of the issue.
    pub const ALL: [TestProblem; 8] =
        [Self::Zdt1, Self::Zdt2, Self::Zdt3, Self::Dtlz2, Self::Bnh, Self::Tnk, Self::Osy, Self::C2Dtlz2];

    /// Parse a name (case-insensitive).
    pub fn parse(s: &str) -> Option<Self> {
        Self::ALL.iter().copied().find(|p| p.name().eq_ignore_ascii_case(s))
    }
    /// Name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Zdt1 => "ZDT1",
            Self::Zdt2 => "ZDT2",
            Self::Zdt3 => "ZDT3",
            Self::Dtlz2 => "DTLZ2",
            Self::Bnh => "BNH",
            Self::Tnk => "TNK",
            Self::Osy => "OSY",
            Self::C2Dtlz2 => "C2DTLZ2",
        }
    }
    /// Generations of the reference experiment (generation 1 = initial population).
    pub fn generations(self) -> u64 {
        match self {
            Self::Zdt1 | Self::Zdt2 | Self::Zdt3 | Self::Dtlz2 => 250,
            _ => 200,
        }
    }
    /// Hypervolume reference point.
    pub fn hv_ref(self) -> Vec<f64> {
        match self {
            Self::Zdt1 | Self::Zdt2 | Self::Zdt3 => vec![1.1, 1.1],
            Self::Dtlz2 | Self::C2Dtlz2 => vec![1.1, 1.1, 1.1],
            Self::Bnh => vec![150.0, 55.0],
            Self::Tnk => vec![1.2, 1.2],
            Self::Osy => vec![-15.0, 85.0],
        }
    }
    /// Reference median hypervolume and [min, max] over seeds 1..11 (the band).
    pub fn hv_band(self) -> (f64, f64, f64) {
        match self {
            Self::Zdt1 => (0.86966, 0.86919, 0.86992),
            Self::Zdt2 => (0.53638, 0.53578, 0.53668),
            Self::Zdt3 => (1.32760, 1.32732, 1.32803),
            Self::Dtlz2 => (0.70669, 0.69849, 0.71229),
            Self::Bnh => (6461.29, 6458.39, 6462.71),
            Self::Tnk => (0.65030, 0.64914, 0.65136),
            Self::Osy => (16828.3, 16081.5, 16844.3),
            Self::C2Dtlz2 => (0.64833, 0.63775, 0.66031),
        }
    }
    /// Instance with bounds.
    pub fn instance(self) -> Test {
        let (lo, hi) = match self {
            Self::Zdt1 | Self::Zdt2 | Self::Zdt3 => (vec![0.0; 30], vec![1.0; 30]),
            Self::Dtlz2 | Self::C2Dtlz2 => (vec![0.0; 12], vec![1.0; 12]),
            Self::Bnh => (vec![0.0, 0.0], vec![5.0, 3.0]),
            Self::Tnk => (vec![0.0, 1e-30], vec![PI, PI]),
            Self::Osy => (vec![0.0, 0.0, 1.0, 0.0, 1.0, 0.0], vec![10.0, 10.0, 5.0, 6.0, 5.0, 10.0]),
        };
        Test { which: self, lo, hi }
    }

    /// Samples of the analytic Pareto front (for IGD).
    pub fn front(self) -> Vec<Vec<f64>> {
        let lin = |n: usize| (0..n).map(move |i| i as f64 / (n - 1) as f64);
        let raw: Vec<Vec<f64>> = match self {
            Self::Zdt1 => lin(1000).map(|f| vec![f, 1.0 - f.sqrt()]).collect(),
            Self::Zdt2 => lin(1000).map(|f| vec![f, 1.0 - f * f]).collect(),
            Self::Zdt3 => lin(20000).map(|f| vec![f, 1.0 - f.sqrt() - f * (10.0 * PI * f).sin()]).collect(),
            Self::Dtlz2 | Self::C2Dtlz2 => {
                let mut v = vec![];
                for i in 0..60 {
                    for j in 0..60 {
                        let (a, b) = (i as f64 / 59.0 * PI / 2.0, j as f64 / 59.0 * PI / 2.0);
                        let f = vec![a.cos() * b.cos(), a.cos() * b.sin(), a.sin()];
                        if self == Self::Dtlz2 || c2_constraint(&f, 0.4) <= 0.0 {
                            v.push(f);
                        }
                    }
                }
                v
            }
            Self::Bnh => lin(1000)
                .map(|t| {
                    let x1 = 5.0 * t;
                    let x2 = x1.min(3.0);
                    vec![4.0 * x1 * x1 + 4.0 * x2 * x2, (x1 - 5.0).powi(2) + (x2 - 5.0).powi(2)]
                })
                .collect(),
            Self::Tnk => lin(20000)
                .filter_map(|t| {
                    let beta = t * PI / 2.0;
                    let r = (1.0 + 0.1 * (16.0 * beta).cos()).sqrt();
                    let (x1, x2) = (r * beta.sin(), r * beta.cos());
                    ((x1 - 0.5).powi(2) + (x2 - 0.5).powi(2) <= 0.5).then(|| vec![x1, x2])
                })
                .collect(),
            Self::Osy => {
                // the five Pareto-optimal regions of Osyczka & Kundu (Deb 2001, §10.3)
                let mut v = vec![];
                let osy = Self::Osy.instance();
                for t in lin(400) {
                    let xs = [
                        [5.0, 1.0, 1.0 + 4.0 * t, 0.0, 5.0, 0.0],
                        [5.0, 1.0, 1.0 + 4.0 * t, 0.0, 1.0, 0.0],
                        [4.056 + (5.0 - 4.056) * t, (4.056 + (5.0 - 4.056) * t - 2.0) / 3.0, 1.0, 0.0, 1.0, 0.0],
                        [0.0, 2.0, 1.0 + 2.732 * t, 0.0, 1.0, 0.0],
                        [t, 2.0 - t, 1.0, 0.0, 1.0, 0.0],
                    ];
                    for x in xs {
                        let e = osy.evaluate(&x);
                        if e.cv.violation <= 1e-9 {
                            v.push(e.f);
                        }
                    }
                }
                v
            }
        };
        super::hv::nondominated_below(&raw, &vec![f64::INFINITY; raw[0].len()])
    }
}

/// pymoo's C2-DTLZ2 constraint value (feasible when ≤ 0).
pub fn c2_constraint(f: &[f64], r: f64) -> f64 {
    let m = f.len();
    let sq: f64 = f.iter().map(|v| v * v).sum();
    let mut v1 = f64::INFINITY;
    for i in 0..m {
        v1 = v1.min((f[i] - 1.0).powi(2) + (sq - f[i] * f[i]) - r * r);
    }
    let a = 1.0 / (m as f64).sqrt();
    let v2: f64 = f.iter().map(|v| (v - a).powi(2)).sum::<f64>() - r * r;
    v1.min(v2)
}

fn dtlz2(x: &[f64], m: usize) -> Vec<f64> {
    let g: f64 = x[m - 1..].iter().map(|v| (v - 0.5).powi(2)).sum();
    let mut f = vec![1.0 + g; m];
    for i in 0..m {
        for j in 0..m - 1 - i {
            f[i] *= (x[j] * PI / 2.0).cos();
        }
        if i > 0 {
            f[i] *= (x[m - 1 - i] * PI / 2.0).sin();
        }
    }
    f
}

impl MooProblem for Test {
    type Info = ();
    type Started = ();
    fn name(&self) -> String {
        self.which.name().into()
    }
    fn lower(&self) -> &[f64] {
        &self.lo
    }
    fn upper(&self) -> &[f64] {
        &self.hi
    }
    fn n_obj(&self) -> usize {
        match self.which {
            TestProblem::Dtlz2 | TestProblem::C2Dtlz2 => 3,
            _ => 2,
        }
    }
    /// Nothing is cheap to start: every evaluation is one formula.
    fn start(&self, _x: &[f64]) -> ((), super::CostHint) {
        ((), super::CostHint::Costly(vec![]))
    }
    fn finish(&self, x: &[f64], _: ()) -> Evaluated<()> {
        let pos = |g: f64| g.max(0.0);
        let (f, v) = match self.which {
            TestProblem::Zdt1 | TestProblem::Zdt2 | TestProblem::Zdt3 => {
                let n = x.len() as f64;
                let g = 1.0 + 9.0 * x[1..].iter().sum::<f64>() / (n - 1.0);
                let q = x[0] / g;
                let h = match self.which {
                    TestProblem::Zdt1 => 1.0 - q.sqrt(),
                    TestProblem::Zdt2 => 1.0 - q * q,
                    _ => 1.0 - q.sqrt() - q * (10.0 * PI * x[0]).sin(),
                };
                (vec![x[0], g * h], 0.0)
            }
            TestProblem::Dtlz2 => (dtlz2(x, 3), 0.0),
            TestProblem::C2Dtlz2 => {
                let f = dtlz2(x, 3);
                let g = c2_constraint(&f, 0.4);
                (f, pos(g))
            }
            TestProblem::Bnh => {
                let f = vec![4.0 * x[0] * x[0] + 4.0 * x[1] * x[1], (x[0] - 5.0).powi(2) + (x[1] - 5.0).powi(2)];
                let g1 = ((x[0] - 5.0).powi(2) + x[1] * x[1] - 25.0) / 25.0;
                let g2 = -((x[0] - 8.0).powi(2) + (x[1] + 3.0).powi(2) - 7.7) / 7.7;
                (f, pos(g1) + pos(g2))
            }
            TestProblem::Tnk => {
                let g1 = -(x[0] * x[0] + x[1] * x[1] - 1.0 - 0.1 * (16.0 * (x[0] / x[1]).atan()).cos());
                let g2 = 2.0 * ((x[0] - 0.5).powi(2) + (x[1] - 0.5).powi(2)) - 1.0;
                (vec![x[0], x[1]], pos(g1) + pos(g2))
            }
            TestProblem::Osy => {
                let f1 = -(25.0 * (x[0] - 2.0).powi(2)
                    + (x[1] - 2.0).powi(2)
                    + (x[2] - 1.0).powi(2)
                    + (x[3] - 4.0).powi(2)
                    + (x[4] - 1.0).powi(2));
                let f2: f64 = x.iter().map(|v| v * v).sum();
                let g = [
                    -(x[0] + x[1] - 2.0) / 2.0,
                    -(6.0 - x[0] - x[1]) / 6.0,
                    -(2.0 - x[1] + x[0]) / 2.0,
                    -(2.0 - x[0] + 3.0 * x[1]) / 2.0,
                    -(4.0 - (x[2] - 3.0).powi(2) - x[3]) / 4.0,
                    -((x[4] - 3.0).powi(2) + x[5] - 4.0) / 4.0,
                ];
                (vec![f1, f2], g.iter().map(|v| pos(*v)).sum())
            }
        };
        Evaluated { f, cv: Infeasibility::from_violation(v), info: () }
    }
}

/// Result of one `moo-test` run.
#[derive(Debug, Clone, serde::Serialize)]
pub struct TestRun {
    /// Problem name.
    pub problem: String,
    /// Seed.
    pub seed: u64,
    /// Exact hypervolume of the final feasible non-dominated set at the problem's reference.
    pub hv: f64,
    /// IGD against the analytic front.
    pub igd: f64,
    /// Evaluations.
    pub evaluations: u64,
    /// Wall time (s).
    pub wall_s: f64,
}

/// Default NSGA-II settings of the validation runs (pop 100, reference operators).
pub fn reference_settings(which: TestProblem, seed: u64, pop: usize) -> super::nsga2::Nsga2Settings {
    let r = which.hv_ref();
    super::nsga2::Nsga2Settings {
        pop_size: pop,
        seed,
        operators: super::operators::Operators::default(),
        eliminate_duplicates: true,
        hv_ideal: vec![0.0; r.len()].into_iter().zip(&r).map(|(_, v)| if *v < 0.0 { 2.0 * v } else { 0.0 }).collect(),
        hv_ref: r,
    }
}

/// Run NSGA-II (crowding survival, SBX: the reference implementation's algorithm, whose
/// hypervolume bands `moo-test` checks) on a test problem and measure HV and IGD of the
/// final feasible front.
pub fn run_test(which: TestProblem, seed: u64, pop: usize, generations: Option<u64>) -> TestRun {
    run_test_with(which, seed, pop, generations, Survival::Crowding, Variation::Sbx)
}

/// [`run_test`] with another survival and variation (e.g. gripopt's defaults,
/// docs/benchmarks.md).
pub fn run_test_with(
    which: TestProblem,
    seed: u64,
    pop: usize,
    generations: Option<u64>,
    survival: Survival,
    variation: Variation,
) -> TestRun {
    let t0 = std::time::Instant::now();
    let settings = reference_settings(which, seed, pop);
    use argmin::core::State;
    let state = super::nsga2::Nsga2State::new().with_max_generations(generations.unwrap_or(which.generations()));
    let solver = super::Nsga2::new(settings).with_survival(survival).with_variation(variation);
    let (_, st) = super::nsga2::execute(which.instance(), solver, state, |e| e).expect("test problem run");
    let wall_s = t0.elapsed().as_secs_f64();
    let front: Vec<Vec<f64>> = st.feasible_front().iter().map(|p| p.eval.f.clone()).collect();
    TestRun {
        problem: which.name().into(),
        seed,
        hv: super::hv::hypervolume(&front, &which.hv_ref()),
        igd: super::hv::igd(&front, &which.front()),
        evaluations: st.evaluations,
        wall_s,
    }
}
