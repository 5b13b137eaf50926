//! The result files of a run folder: `pareto.csv` (the final feasible non-dominated designs,
//! deterministic), `pareto_timings.csv` (their wall-clock stage timings, not deterministic),
//! `population.csv` (the whole final population with discard stages and reasons),
//! `history.csv`, and the plots `pareto_matrix.svg` and `hypervolume.svg`.

use super::gripper::{GripperInfo, GripperProblem};
use crate::Result;
use crate::fsutil::write_atomic;
use crate::optim::Nsga2State;
use crate::optim::Individual;
use std::fmt::Write as _;
use std::path::Path;

fn opt(v: Option<f64>) -> String {
    v.map(|x| format!("{x}")).unwrap_or_default()
}

/// The final feasible non-dominated designs, sorted by id.
pub fn final_front(st: &Nsga2State<GripperInfo>) -> Vec<&Individual<GripperInfo>> {
    let mut f = st.feasible_front();
    f.sort_by_key(|p| p.id);
    f
}

/// Write every result file of the final state `st` into the run folder `out`.
pub fn write_outputs(out: &Path, gp: &GripperProblem, st: &Nsga2State<GripperInfo>) -> Result<()> {
    let front = final_front(st);
    let mut csv = String::from("id,generation,l21,b,t22,r,p,psi_deg,l11,l12,l22,l_hand,max_offset,alpha,mean_force,t_stab,sim_steps,sim_rhs_evals,force_model\n");
    let force_model = gp.problem.scene.criteria.force_model.as_str(); // D22: which forces define alpha, mean_force
    let mut tim = String::from("id,stage01_s,stage2_s,stage3_s\n");
    for ind in &front {
        let i = &ind.eval.info;
        let x = &ind.x;
        let l = i.lengths.unwrap_or([f64::NAN; 3]);
        let w = i.sim_work.map(|w| (w[0].to_string(), w[1].to_string())).unwrap_or_default();
        let _ = writeln!(
            csv,
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            ind.id, ind.generation, x[0], x[1], x[2], x[3], x[4], x[5], l[0], l[1], l[2], i.l_hand,
            opt(i.objectives[0]), opt(i.objectives[1]), opt(i.objectives[2]), opt(i.objectives[3]), w.0, w.1, force_model
        );
        let _ = writeln!(tim, "{},{},{},{}", ind.id, i.stage_seconds[1], i.stage_seconds[2], i.stage_seconds[3]);
    }
    write_atomic(&out.join("pareto.csv"), csv.as_bytes())?;
    write_atomic(&out.join("pareto_timings.csv"), tim.as_bytes())?;
    let mut pop = String::from("id,generation,rank,feasible,failed_stage,violation,reason,l21,b,t22,r,p,psi_deg,max_offset,alpha,mean_force,t_stab\n");
    let mut order: Vec<usize> = (0..st.population.len()).collect();
    order.sort_by_key(|&k| (st.rank[k], st.population[k].id));
    for k in order {
        let ind = &st.population[k];
        let i = &ind.eval.info;
        let x = &ind.x;
        let _ = writeln!(
            pop,
            "{},{},{},{},{},{},\"{}\",{},{},{},{},{},{},{},{},{},{}",
            ind.id, ind.generation, st.rank[k], ind.eval.cv.is_feasible(), i.failed_stage.map(|s| s.to_string()).unwrap_or_default(),
            opt(i.violation), i.reason.clone().unwrap_or_default().replace('"', "'"), x[0], x[1], x[2], x[3], x[4], x[5],
            opt(i.objectives[0]), opt(i.objectives[1]), opt(i.objectives[2]), opt(i.objectives[3])
        );
    }
    write_atomic(&out.join("population.csv"), pop.as_bytes())?;
    let mut hist = String::from("generation,evaluations,feasible,hypervolume\n");
    for (g, (hv, fe)) in st.hv_history.iter().zip(&st.feasible_history).enumerate() {
        let _ = writeln!(hist, "{},{},{},{}", g + 1, (g as u64 + 1) * st.population.len() as u64, fe, hv);
    }
    write_atomic(&out.join("history.csv"), hist.as_bytes())?;
    super::plots::pareto_matrix(&out.join("pareto_matrix.svg"), gp, st)?;
    super::plots::hypervolume(&out.join("hypervolume.svg"), &st.hv_history)?;
    Ok(())
}
