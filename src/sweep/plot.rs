//! SVG plots of a sweep: line plots for one varied name, maps coloured by verdict or by a
//! chosen record value for two, and one map per slice of the third name for three.

use super::{Boundary, Row, SweepSpec};
use crate::error::{Error, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::{Path, PathBuf};

fn pe<E: std::fmt::Display>(path: &Path) -> impl Fn(E) -> Error + '_ {
    move |x| Error::RunDir { path: path.to_path_buf(), message: format!("plot: {x}") }
}

const VERDICT_COLOURS: &[(&str, RGBColor)] = &[
    ("pass", RGBColor(30, 30, 30)),
    ("singular_open", RGBColor(40, 90, 220)),
    ("singular_closing", RGBColor(40, 170, 60)),
    ("mode_change", RGBColor(220, 40, 40)),
    ("not_mountable", RGBColor(150, 150, 150)),
    ("no_open_pose", RGBColor(200, 200, 200)),
    ("no_closed_pose", RGBColor(240, 160, 40)),
    ("invalid", RGBColor(255, 255, 255)),
    ("spring", RGBColor(120, 60, 20)),
    ("no_grasp_pose", RGBColor(240, 160, 40)),
    ("singular_forces", RGBColor(120, 60, 20)),
    ("force_positiveness", RGBColor(160, 60, 200)),
    ("palm_force", RGBColor(250, 120, 180)),
    ("no_form_closure", RGBColor(100, 200, 220)),
    ("impact", RGBColor(235, 200, 0)),
    ("fold", RGBColor(0, 150, 150)),
    ("force", RGBColor(220, 40, 40)),
    ("static_force", RGBColor(150, 0, 0)),
    ("no_stability", RGBColor(100, 100, 255)),
    ("singular_dynamic", RGBColor(40, 170, 60)),
    ("aborted", RGBColor(90, 90, 90)),
    ("initial_penetration", RGBColor(255, 0, 255)),
    ("no_equilibrium", RGBColor(90, 90, 90)),
    ("object_moved", RGBColor(255, 120, 0)),
    ("free_scene_aborted", RGBColor(60, 60, 60)),
    ("no_offset_grasp", RGBColor(240, 160, 40)),
];

/// The colour of a verdict class.
pub fn verdict_colour(v: &str) -> RGBColor {
    VERDICT_COLOURS.iter().find(|(k, _)| *k == v).map(|c| c.1).unwrap_or(RGBColor(0, 0, 0))
}

/// Viridis-like colour for t in [0, 1].
fn ramp(t: f64) -> RGBColor {
    const S: [(f64, f64, f64); 5] =
        [(68.0, 1.0, 84.0), (59.0, 82.0, 139.0), (33.0, 145.0, 140.0), (94.0, 201.0, 98.0), (253.0, 231.0, 37.0)];
    let t = if t.is_finite() { t.clamp(0.0, 1.0) } else { 0.0 };
    let x = t * 4.0;
    let i = (x.floor() as usize).min(3);
    let f = x - i as f64;
    let (a, b) = (S[i], S[i + 1]);
    let m = |p: f64, q: f64| (p + (q - p) * f).round() as u8;
    RGBColor(m(a.0, b.0), m(a.1, b.1), m(a.2, b.2))
}

fn range(v: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) =
        v.filter(|x| x.is_finite()).fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| (a.min(x), b.max(x)));
    if !lo.is_finite() {
        (0.0, 1.0)
    } else if hi > lo {
        (lo, hi)
    } else {
        (lo - 0.5 * lo.abs().max(1e-12), hi + 0.5 * hi.abs().max(1e-12))
    }
}

/// Draw every plot for the sweep, each written atomically and never through a link
/// ([`crate::fsutil::write_rendered`]); returns the files written.
pub fn plot_all(
    dir: &Path,
    spec: &SweepSpec,
    rows: &[Row],
    ys: &[String],
    colours: &[String],
    bounds: &[Boundary],
) -> Result<Vec<PathBuf>> {
    let mut out = Vec::new();
    let names = planned(spec, ys, colours);
    if is_line(spec) {
        for (y, name) in ys.iter().zip(&names) {
            let f = dir.join(name);
            crate::fsutil::write_rendered(&f, |svg| line(svg, &f, spec, rows, y, bounds))?;
            out.push(f);
        }
    } else {
        let cs = std::iter::once(None).chain(colours.iter().map(|c| Some(c.as_str())));
        for (c, name) in cs.zip(&names) {
            let f = dir.join(name);
            crate::fsutil::write_rendered(&f, |svg| maps(svg, &f, spec, rows, c))?;
            out.push(f);
        }
    }
    Ok(out)
}

/// One varied name with more than one value: line plots (else maps or slices).
pub fn is_line(spec: &SweepSpec) -> bool {
    spec.vary.len() == 1 || (spec.vary[0].n > 1 && spec.vary[1..].iter().all(|v| v.n == 1))
}

/// The names of the files [`plot_all`] writes, in its order.
pub fn planned(spec: &SweepSpec, ys: &[String], colours: &[String]) -> Vec<String> {
    if is_line(spec) {
        return ys.iter().map(|y| format!("line_{}.svg", y.replace('+', "_"))).collect();
    }
    let kind = if spec.vary.len() == 2 { "map" } else { "slices" };
    std::iter::once(format!("{kind}_verdict.svg")).chain(colours.iter().map(|c| format!("{kind}_{c}.svg"))).collect()
}

/// Line plot of the `+`-separated keys `ys` against the one varied name; markers coloured by verdict.
fn line(svg: &mut String, path: &Path, spec: &SweepSpec, rows: &[Row], ys: &str, bounds: &[Boundary]) -> Result<()> {
    let e = pe(path);
    let keys: Vec<&str> = ys.split('+').collect();
    let xs: Vec<f64> = rows.iter().map(|r| r.values[0]).collect();
    let (x0, x1) = range(xs.iter().copied());
    let (y0, y1) = range(keys.iter().flat_map(|k| rows.iter().filter_map(move |r| r.num(k))));
    let pad = 0.05 * (y1 - y0);
    let root = SVGBackend::with_string(svg, (800, 520)).into_drawing_area();
    root.fill(&WHITE).map_err(&e)?;
    let verdicts = distinct(rows);
    let title = format!(
        "{} against {} ({} points; markers: verdict {})",
        ys,
        spec.vary[0].name,
        rows.len(),
        verdicts.join(", ")
    );
    let mut ch = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 15))
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(x0..x1, (y0 - pad)..(y1 + pad))
        .map_err(&e)?;
    ch.configure_mesh().x_desc(spec.vary[0].name.as_str()).y_desc(ys).draw().map_err(&e)?;
    let styles = [BLUE, RED, GREEN, MAGENTA, CYAN];
    for (i, k) in keys.iter().enumerate() {
        let c = styles[i % styles.len()];
        let pts: Vec<(f64, f64)> = rows.iter().filter_map(|r| r.num(k).map(|y| (r.values[0], y))).collect();
        ch.draw_series(LineSeries::new(pts.clone(), c.stroke_width(2)))
            .map_err(&e)?
            .label(*k)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], c.stroke_width(2)));
        ch.draw_series(
            rows.iter()
                .filter_map(|r| r.num(k).map(|y| Circle::new((r.values[0], y), 4, verdict_colour(r.verdict).filled()))),
        )
        .map_err(&e)?;
    }
    for b in bounds {
        let xb = 0.5 * (b.lo + b.hi);
        ch.draw_series(std::iter::once(PathElement::new(vec![(xb, y0 - pad), (xb, y1 + pad)], BLACK.stroke_width(1))))
            .map_err(&e)?
            .label(format!("{} = {:.5} ({} | {})", b.name, xb, b.verdict_lo, b.verdict_hi))
            .legend(|(x, y)| PathElement::new(vec![(x, y - 6), (x, y + 6)], BLACK));
    }
    ch.configure_series_labels().background_style(WHITE.mix(0.8)).border_style(BLACK).draw().map_err(&e)?;
    root.present().map_err(&e)?;
    Ok(())
}

fn distinct(rows: &[Row]) -> Vec<&'static str> {
    let mut v: Vec<&'static str> = Vec::new();
    for r in rows {
        if !v.contains(&r.verdict) {
            v.push(r.verdict);
        }
    }
    v
}

/// One map (2 names) or one map per value of the third name, coloured by verdict or by `key`.
fn maps(svg: &mut String, path: &Path, spec: &SweepSpec, rows: &[Row], key: Option<&str>) -> Result<()> {
    let e = pe(path);
    let n3 = if spec.vary.len() == 3 { spec.vary[2].n } else { 1 };
    let panels: Vec<usize> = if n3 <= 12 { (0..n3).collect() } else { (0..12).map(|i| i * (n3 - 1) / 11).collect() };
    let cols = (panels.len() as f64).sqrt().ceil() as usize;
    let nrows = panels.len().div_ceil(cols);
    let root = SVGBackend::with_string(svg, (420 * cols as u32 + 170, 380 * nrows as u32 + 40)).into_drawing_area();
    root.fill(&WHITE).map_err(&e)?;
    let (vmin, vmax) = match key {
        Some(k) => range(rows.iter().filter_map(|r| r.num(k))),
        None => (0.0, 1.0),
    };
    let title = match key {
        None => format!("verdict over {}", spec.vary.iter().map(|v| v.name.as_str()).collect::<Vec<_>>().join(", ")),
        Some(k) => format!("{k} (min {vmin:.4e}, max {vmax:.4e}; grey = not computed)"),
    };
    let root = root.titled(&title, ("sans-serif", 18)).map_err(&e)?;
    let (main, side) = root.split_horizontally(420 * cols as u32);
    let cells = main.split_evenly((nrows, cols));
    let per = spec.vary[0].n * spec.vary[1].n;
    for (pi, &slice) in panels.iter().enumerate() {
        let sub = &rows[slice * per..(slice + 1) * per];
        let cap = if spec.vary.len() == 3 {
            format!("{} = {:.4}", spec.vary[2].name, sub[0].values[2])
        } else {
            String::new()
        };
        panel(&cells[pi], spec, sub, key, (vmin, vmax), &cap).map_err(&e)?;
    }
    legend(&side, rows, key, (vmin, vmax)).map_err(&e)?;
    root.present().map_err(&e)?;
    Ok(())
}

type DrawResult<T> = std::result::Result<T, DrawingAreaErrorKind<std::io::Error>>;

fn half_step(v: &super::Vary) -> f64 {
    if v.n > 1 {
        0.5 * (v.hi - v.lo) / (v.n - 1) as f64
    } else {
        0.5 * v.lo.abs().max(1e-9) * 0.05
    }
}

fn panel(
    area: &DrawingArea<SVGBackend, Shift>,
    spec: &SweepSpec,
    rows: &[Row],
    key: Option<&str>,
    (vmin, vmax): (f64, f64),
    cap: &str,
) -> DrawResult<()> {
    let (vx, vy) = (&spec.vary[0], &spec.vary[1]);
    let (hx, hy) = (half_step(vx), half_step(vy));
    let mut ch = ChartBuilder::on(area)
        .caption(cap, ("sans-serif", 14))
        .margin(8)
        .x_label_area_size(35)
        .y_label_area_size(55)
        .build_cartesian_2d((vx.lo - hx)..(vx.hi + hx), (vy.lo - hy)..(vy.hi + hy))?;
    ch.configure_mesh()
        .disable_mesh()
        .x_desc(vx.name.as_str())
        .y_desc(vy.name.as_str())
        .x_labels(5)
        .y_labels(5)
        .draw()?;
    ch.draw_series(rows.iter().map(|r| {
        let c = match key {
            None => verdict_colour(r.verdict),
            Some(k) => match r.num(k) {
                Some(v) => ramp((v - vmin) / (vmax - vmin)),
                None => RGBColor(225, 225, 225),
            },
        };
        let (x, y) = (r.values[0], r.values[1]);
        Rectangle::new([(x - hx, y - hy), (x + hx, y + hy)], c.filled())
    }))?;
    Ok(())
}

fn legend(
    area: &DrawingArea<SVGBackend, Shift>,
    rows: &[Row],
    key: Option<&str>,
    (vmin, vmax): (f64, f64),
) -> DrawResult<()> {
    let font = ("sans-serif", 13).into_font();
    match key {
        None => {
            for (i, v) in distinct(rows).iter().enumerate() {
                let y = 40 + 22 * i as i32;
                area.draw(&Rectangle::new([(8, y), (24, y + 14)], verdict_colour(v).filled()))?;
                area.draw(&Rectangle::new([(8, y), (24, y + 14)], BLACK.stroke_width(1)))?;
                area.draw(&Text::new(v.to_string(), (30, y), font.clone()))?;
            }
        }
        Some(_) => {
            for i in 0..100 {
                let t = 1.0 - i as f64 / 99.0;
                let y = 40 + 3 * i;
                area.draw(&Rectangle::new([(10, y), (30, y + 3)], ramp(t).filled()))?;
            }
            area.draw(&Text::new(format!("{vmax:.4e}"), (36, 36), font.clone()))?;
            area.draw(&Text::new(format!("{vmin:.4e}"), (36, 330), font.clone()))?;
        }
    }
    Ok(())
}
