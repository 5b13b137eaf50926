//! SVG plots of a run: 4-objective scatter matrix and hypervolume per generation.

use super::gripper::{GripperInfo, GripperProblem};
use crate::eval::OBJECTIVES;
use crate::optim::Nsga2State;
use crate::{Error, Result};
use plotters::prelude::*;
use std::path::Path;

/// A plot drawn into a text ([`crate::fsutil::write_rendered`] writes it atomically).
type Area<'a> = DrawingArea<SVGBackend<'a>, plotters::coord::Shift>;

/// The error of drawing into `path`.
fn plot_error<E: std::error::Error + Send + Sync + 'static>(path: &Path) -> impl Fn(E) -> Error + '_ {
    move |x| Error::Plot { path: path.to_path_buf(), source: Box::new(x) }
}

/// Scatter matrix of the four objectives (natural sense) of the feasible final population:
/// the non-dominated front in red, other feasible designs in grey, the problem's nominal
/// design as a blue cross; axis names say which way is better.
pub fn pareto_matrix(path: &Path, gp: &GripperProblem, st: &Nsga2State<GripperInfo>) -> Result<()> {
    let draw = |svg: &mut String| {
        draw_pareto_matrix(SVGBackend::with_string(svg, (1000, 1000)).into_drawing_area(), path, gp, st)
    };
    crate::fsutil::write_rendered(path, draw)
}

fn draw_pareto_matrix(root: Area<'_>, path: &Path, gp: &GripperProblem, st: &Nsga2State<GripperInfo>) -> Result<()> {
    let names = OBJECTIVES.map(|o| o.axis());
    let scale = OBJECTIVES.map(|o| o.shown.1);
    let nominal = {
        use crate::optim::MooProblem;
        let ev = gp.evaluate(&gp.problem.nominal.to_array());
        let o = ev.info.record.objectives();
        [0, 1, 2, 3].map(|k| o[k].unwrap_or(f64::NAN) * scale[k])
    };
    let pts: Vec<([f64; 4], bool)> = st
        .population
        .iter()
        .zip(&st.rank)
        .filter(|(p, _)| p.eval.cv.is_feasible())
        .map(|(p, r)| {
            let o = &p.eval.info.record.objectives();
            ([0, 1, 2, 3].map(|k| o[k].unwrap_or(f64::NAN) * scale[k]), *r == 0)
        })
        .collect();
    root.fill(&WHITE).map_err(plot_error(path))?;
    let title = format!(
        "generation {}: {} feasible; red = Pareto front ({}), grey = dominated, blue cross = nominal design",
        st.generation,
        pts.len(),
        pts.iter().filter(|p| p.1).count()
    );
    let root = root.titled(&title, ("sans-serif", 16)).map_err(plot_error(path))?;
    let cells = root.split_evenly((4, 4));
    for (idx, cell) in cells.iter().enumerate() {
        let (row, col) = (idx / 4, idx % 4);
        let range = |k: usize| {
            let (lo, hi) = pts
                .iter()
                .map(|p| p.0[k])
                .filter(|v| v.is_finite())
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(v), b.max(v)));
            if lo.is_finite() && hi > lo {
                let m = 0.05 * (hi - lo);
                (lo - m)..(hi + m)
            } else if lo.is_finite() {
                (lo - 1.0)..(hi + 1.0)
            } else {
                0.0..1.0
            }
        };
        let mut chart = ChartBuilder::on(cell)
            .margin(4)
            .x_label_area_size(if row == 3 { 30 } else { 12 })
            .y_label_area_size(if col == 0 { 45 } else { 12 })
            .build_cartesian_2d(range(col), range(row))
            .map_err(plot_error(path))?;
        let mut mesh = chart.configure_mesh();
        mesh.x_labels(3).y_labels(3);
        if row == 3 {
            mesh.x_desc(names[col].as_str());
        }
        if col == 0 {
            mesh.y_desc(names[row].as_str());
        }
        mesh.draw().map_err(plot_error(path))?;
        if row == col {
            continue;
        }
        chart
            .draw_series(
                pts.iter()
                    .filter(|p| !p.1)
                    .map(|p| Circle::new((p.0[col], p.0[row]), 2, RGBColor(150, 150, 150).filled())),
            )
            .map_err(plot_error(path))?;
        chart
            .draw_series(pts.iter().filter(|p| p.1).map(|p| Circle::new((p.0[col], p.0[row]), 3, RED.filled())))
            .map_err(plot_error(path))?;
        if nominal[col].is_finite() && nominal[row].is_finite() {
            chart
                .draw_series(std::iter::once(Cross::new((nominal[col], nominal[row]), 5, BLUE.stroke_width(2))))
                .map_err(plot_error(path))?;
        }
    }
    root.present().map_err(plot_error(path))?;
    Ok(())
}

/// Normalised hypervolume per generation: the population's feasible front (can dip when
/// the survival drops a front member), the archive of every feasible non-dominated design
/// (never falls) and the reported front, pareto.csv (the archive's best designs, at most
/// the population size; its generations before issue 42 are not drawn).
pub fn hypervolume(path: &Path, hv: &[f64], archive_hv: &[f64], pareto_hv: &[f64]) -> Result<()> {
    let draw = |svg: &mut String| {
        let root = SVGBackend::with_string(svg, (800, 500)).into_drawing_area();
        draw_hypervolume(root, path, [hv, archive_hv, pareto_hv])
    };
    crate::fsutil::write_rendered(path, draw)
}

/// The three curves of [`hypervolume`]: the population's, the archive's, pareto.csv's.
fn draw_hypervolume(root: Area<'_>, path: &Path, [hv, archive_hv, pareto_hv]: [&[f64]; 3]) -> Result<()> {
    root.fill(&WHITE).map_err(plot_error(path))?;
    let ymax = hv.iter().chain(archive_hv).cloned().filter(|v| v.is_finite()).fold(1e-6, f64::max) * 1.1;
    let green = RGBColor(0, 140, 60);
    let mut chart = ChartBuilder::on(&root)
        .caption("hypervolume (normalised objectives; higher is better)", ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(35)
        .y_label_area_size(60)
        .build_cartesian_2d(1f64..(hv.len().max(2) as f64), 0f64..ymax)
        .map_err(plot_error(path))?;
    chart.configure_mesh().x_desc("generation").y_desc("hypervolume").draw().map_err(plot_error(path))?;
    chart
        .draw_series(LineSeries::new(
            hv.iter().enumerate().map(|(g, v)| (g as f64 + 1.0, if v.is_finite() { *v } else { 0.0 })),
            BLUE.stroke_width(2),
        ))
        .map_err(plot_error(path))?
        .label("population's front (history.csv's hypervolume)")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 15, y)], BLUE));
    chart
        .draw_series(LineSeries::new(
            archive_hv.iter().enumerate().filter(|(_, v)| v.is_finite()).map(|(g, v)| (g as f64 + 1.0, *v)),
            RED.stroke_width(2),
        ))
        .map_err(plot_error(path))?
        .label("archive.csv (every non-dominated design found)")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 15, y)], RED));
    chart
        .draw_series(LineSeries::new(
            pareto_hv.iter().enumerate().filter(|(_, v)| v.is_finite()).map(|(g, v)| (g as f64 + 1.0, *v)),
            green.stroke_width(2),
        ))
        .map_err(plot_error(path))?
        .label("pareto.csv (the reported front: the archive's best, at most the population size)")
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 15, y)], green));
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::LowerRight)
        .background_style(WHITE)
        .border_style(BLACK)
        .draw()
        .map_err(plot_error(path))?;
    root.present().map_err(plot_error(path))?;
    Ok(())
}
