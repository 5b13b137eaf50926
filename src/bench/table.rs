//! The work-precision table as CSV, as a printed table, and as an SVG plot.

use super::say;
use crate::{Error, Result};
use std::io::Write as _;
use std::path::Path;

/// One row of the work-precision table.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Row {
    /// Method label.
    pub method: &'static str,
    /// Relative tolerance.
    pub rtol: f64,
    /// Minimum CPU time per simulation, s.
    pub cpu_min: f64,
    /// Median CPU time per simulation, s.
    pub cpu_med: f64,
    /// Accepted steps.
    pub steps: u64,
    /// Right-hand-side evaluations.
    pub rhs: u64,
    /// Relative error of the time of first contact.
    pub err_t_first: f64,
    /// Relative error of E_cyl.
    pub err_e_cyl: f64,
    /// Relative error of t_stab.
    pub err_t_stab: f64,
    /// Largest relative error of the two forces at t_stab (NaN without t_stab).
    pub err_force: f64,
    /// Same verdict as the reference.
    pub verdict_same: bool,
}

impl Row {
    /// The relative errors against the reference: t of first contact, E_cyl, t_stab, forces.
    fn errors(&self) -> [f64; 4] {
        [self.err_t_first, self.err_e_cyl, self.err_t_stab, self.err_force]
    }
}

/// Writes the CSV file `path` (its folder created if need be) atomically, never through a
/// link ([`crate::fsutil::AtomicFile`]): the `header` line, then each of `lines` (without
/// their line breaks).
pub(super) fn write_csv_lines(path: &Path, header: &str, lines: impl IntoIterator<Item = String>) -> Result<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, "cannot create", e))?;
    }
    let io = |e| Error::io(path, "cannot write", e);
    let mut w = crate::fsutil::AtomicFile::create(path)?;
    writeln!(w, "{header}").map_err(io)?;
    for line in lines {
        writeln!(w, "{line}").map_err(io)?;
    }
    w.commit()
}

/// Writes `rows` as CSV to `path` (its folder created if need be).
pub fn write_csv(rows: &[Row], path: &Path) -> Result<()> {
    let header = "method,rtol,cpu_min_s,cpu_median_s,steps,rhs_evals,err_t_first_contact,err_e_cyl,err_t_stab,err_final_forces,same_verdict";
    let lines = rows.iter().map(|r| {
        let errors = r.errors().map(|e| format!("{e:e}")).join(",");
        format!(
            "{},{:e},{:e},{:e},{},{},{errors},{}",
            r.method, r.rtol, r.cpu_min, r.cpu_med, r.steps, r.rhs, r.verdict_same
        )
    });
    write_csv_lines(path, header, lines)
}

/// Writes `rows` as a table to `out`.
pub fn print_table(rows: &[Row], out: super::Out) -> Result<()> {
    say!(
        out,
        "{:<8} {:>7} {:>10} {:>10} {:>7} {:>8} {:>10} {:>10} {:>10} {:>10} verdict",
        "method",
        "rtol",
        "cpu min",
        "cpu med",
        "steps",
        "rhs",
        "e(t_fc)",
        "e(E_cyl)",
        "e(t_stab)",
        "e(f_stab)"
    );
    for r in rows {
        let errors = r.errors().map(|e| format!("{e:>10.2e}")).join(" ");
        say!(
            out,
            "{:<8} {:>7.0e} {:>8.3}ms {:>8.3}ms {:>7} {:>8} {errors} {}",
            r.method,
            r.rtol,
            r.cpu_min * 1e3,
            r.cpu_med * 1e3,
            r.steps,
            r.rhs,
            if r.verdict_same { "same" } else { "DIFFERS" }
        );
    }
    Ok(())
}

/// Labels of `rows` in order, each once per run of equal labels.
fn labels(rows: &[Row]) -> Vec<&'static str> {
    let mut labels: Vec<&'static str> = rows.iter().map(|r| r.method).collect();
    labels.dedup();
    labels
}

/// Writes to `out`, per method, the cheapest run (median CPU) with t_stab within 1e-5.
pub fn print_targets(rows: &[Row], out: super::Out) -> Result<()> {
    for m in labels(rows) {
        let best = rows
            .iter()
            .filter(|r| r.method == m && r.err_t_stab <= 1e-5)
            .min_by(|a, b| a.cpu_med.total_cmp(&b.cpu_med));
        match best {
            Some(r) => say!(
                out,
                "{m}: t_stab within 1e-5 at rtol {:e} in {:.3} ms (min {:.3} ms)",
                r.rtol,
                r.cpu_med * 1e3,
                r.cpu_min * 1e3
            ),
            None => say!(out, "{m}: no tolerance reached 1e-5 on t_stab"),
        }
    }
    Ok(())
}

/// Plots median CPU time against the relative error in t_stab, one line per method, to the
/// SVG file `path`.
pub fn plot(rows: &[Row], path: &Path) -> Result<()> {
    let pts: Vec<&Row> = rows.iter().filter(|r| r.err_t_stab.is_finite() && r.err_t_stab > 0.0).collect();
    let series: Vec<(String, Vec<(f64, f64)>)> = labels(rows)
        .into_iter()
        .map(|m| (m.to_string(), pts.iter().filter(|r| r.method == m).map(|r| (r.err_t_stab, r.cpu_med)).collect()))
        .collect();
    work_precision_chart(
        path,
        "work-precision: nominal grasp to t_stab",
        "relative error in t_stab",
        &series,
        (1e-14, 1.0),
        (1e-4, 1e-3),
    )
}

/// A log–log work-precision chart (median CPU time against an error) with one line per
/// `(label, points)` series, to the SVG file `path` (written atomically, never through a
/// link); the axes cover at least `x0` and `y0`.
pub fn work_precision_chart(
    path: &Path,
    caption: &str,
    x_desc: &str,
    series: &[(String, Vec<(f64, f64)>)],
    x0: (f64, f64),
    y0: (f64, f64),
) -> Result<()> {
    crate::fsutil::write_rendered(path, |svg| draw_chart(svg, path, caption, x_desc, series, x0, y0))
}

fn draw_chart(
    svg: &mut String,
    path: &Path,
    caption: &str,
    x_desc: &str,
    series: &[(String, Vec<(f64, f64)>)],
    x0: (f64, f64),
    y0: (f64, f64),
) -> Result<()> {
    use plotters::prelude::*;
    let e = |e| Error::bench_from(format!("plot {}", path.display()), e);
    let root = SVGBackend::with_string(svg, (900, 600)).into_drawing_area();
    root.fill(&WHITE).map_err(e)?;
    let all = series.iter().flat_map(|(_, p)| p.iter());
    let (xmin, xmax, ymin, ymax) =
        all.fold((x0.0, x0.1, y0.0, y0.1), |(a, b, c, d), &(x, y)| (a.min(x), b.max(x), c.min(y), d.max(y)));
    let mut chart = ChartBuilder::on(&root)
        .caption(caption, ("sans-serif", 22))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d((xmin * 0.5..xmax * 2.0).log_scale(), (ymin * 0.8..ymax * 1.25).log_scale())
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc("CPU time, median (s)")
        .x_label_formatter(&|v| format!("{v:.0e}"))
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .draw()
        .map_err(e)?;
    let palette = [RED, BLUE, GREEN, MAGENTA, CYAN, BLACK, RGBColor(255, 140, 0)];
    for (j, (label, pts)) in series.iter().filter(|(_, p)| !p.is_empty()).enumerate() {
        let color = palette[j % palette.len()];
        chart
            .draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))
            .map_err(e)?
            .label(label.clone())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color));
        chart.draw_series(pts.iter().map(|&(x, y)| Circle::new((x, y), 4, color.filled()))).map_err(e)?;
    }
    chart.configure_series_labels().border_style(BLACK).background_style(WHITE).draw().map_err(e)?;
    root.present().map_err(e)?;
    Ok(())
}
