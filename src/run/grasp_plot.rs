//! SVG plot of one grasp (thesis figs 4.11–4.12): joint angles, contact normal forces, and
//! the hand force with its low-pass filtered value of the force criterion, against time.

use crate::error::{Error, Result};
use crate::sim::Sample;
use plotters::prelude::*;
use std::path::Path;

/// Plot `samples` (one design's trajectory) into the SVG file `path` under `title`
/// (written atomically, never through a link: [`crate::fsutil::write_rendered`]).
pub fn grasp_plot(path: &Path, title: &str, samples: &[Sample]) -> Result<()> {
    crate::fsutil::write_rendered(path, |svg| draw(svg, path, title, samples))
}

fn draw(svg: &mut String, path: &Path, title: &str, samples: &[Sample]) -> Result<()> {
    let e = |x: &dyn std::fmt::Display| Error::Plot { path: path.to_path_buf(), source: x.to_string().into() };
    let root = SVGBackend::with_string(svg, (900, 1000)).into_drawing_area();
    root.fill(&WHITE).map_err(|x| e(&x))?;
    let panels = root.split_evenly((3, 1));
    let tmax = samples.last().map_or(1e-3, |x| x.t).max(1e-6) * 1e3;
    let range = |vals: &mut dyn Iterator<Item = f64>| {
        let (lo, hi) =
            vals.filter(|v| v.is_finite()).fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(v), b.max(v)));
        if lo.is_finite() {
            let pad = 0.05 * (hi - lo).max(1e-9);
            (lo - pad, hi + pad)
        } else {
            (0.0, 1.0)
        }
    };
    // joint angles (deg)
    let ang = |x: &Sample| [x.q[0].to_degrees(), x.q[1].to_degrees(), x.theta2.to_degrees()];
    let (lo, hi) = range(&mut samples.iter().flat_map(ang));
    let angle = |k: usize| samples.iter().map(|x| (x.t * 1e3, ang(x)[k])).collect();
    let caption = format!("{title}: joint angles");
    let series = vec![("q11", RED, angle(0)), ("q21 = theta1", BLUE, angle(1)), ("theta2", GREEN, angle(2))];
    draw_panel(&panels[0], tmax, Panel { caption: &caption, font: 18, y: lo..hi, unit: "deg", series }, &e)?;
    // contact normal forces (N), clipped at 200 N so the settled level stays readable
    let fmax = samples.iter().map(|x| x.normal[0].max(x.normal[1])).fold(1.0, f64::max).min(200.0);
    let normal = |k: usize| samples.iter().map(|x| (x.t * 1e3, x.normal[k].min(fmax * 1.05))).collect();
    let caption = "contact normal forces (N, clipped at 200)";
    let series = vec![("proximal", RED, normal(0)), ("distal", BLUE, normal(1))];
    draw_panel(&panels[1], tmax, Panel { caption, font: 18, y: 0.0..fmax * 1.05, unit: "N", series }, &e)?;
    // hand force on the object, filtered (§9.3) and raw, the raw clipped to a few times the
    // filtered range so that the filtered curve the criterion reads stays visible
    let fscale = samples.iter().map(|x| x.filtered_fy.abs()).filter(|v| v.is_finite()).fold(1.0, f64::max);
    let clip = |v: f64| v.clamp(-3.0 * fscale, 3.0 * fscale);
    let (lo, hi) = range(&mut samples.iter().flat_map(|x| [clip(x.hand_fy), x.filtered_fy]));
    let caption = "hand force F_hand,y on the object (N): low-pass filtered (force criterion) and raw, clipped";
    let series = vec![
        ("raw", RGBColor(170, 170, 170), samples.iter().map(|x| (x.t * 1e3, clip(x.hand_fy))).collect()),
        ("filtered", BLACK, samples.iter().map(|x| (x.t * 1e3, x.filtered_fy)).collect()),
    ];
    draw_panel(&panels[2], tmax, Panel { caption, font: 16, y: lo..hi, unit: "N", series }, &e)?;
    root.present().map_err(|x| e(&x))?;
    Ok(())
}

/// One line of a panel: its name, colour and points (t in ms, value).
type Series<'a> = (&'a str, RGBColor, Vec<(f64, f64)>);

/// One panel of the plot: each series against time.
struct Panel<'a> {
    caption: &'a str,
    font: u32,
    y: std::ops::Range<f64>,
    unit: &'a str,
    series: Vec<Series<'a>>,
}

/// Draws panel `p` on `area`, time 0..`tmax` ms, with its legend.
fn draw_panel(
    area: &DrawingArea<SVGBackend<'_>, plotters::coord::Shift>,
    tmax: f64,
    p: Panel<'_>,
    e: &dyn Fn(&dyn std::fmt::Display) -> Error,
) -> Result<()> {
    let mut c = ChartBuilder::on(area)
        .caption(p.caption, ("sans-serif", p.font))
        .margin(10)
        .x_label_area_size(30)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..tmax, p.y)
        .map_err(|x| e(&x))?;
    c.configure_mesh().x_desc("t (ms)").y_desc(p.unit).draw().map_err(|x| e(&x))?;
    for (name, col, points) in p.series {
        c.draw_series(LineSeries::new(points, col))
            .map_err(|x| e(&x))?
            .label(name)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 15, y)], col));
    }
    c.configure_series_labels().background_style(WHITE).border_style(BLACK).draw().map_err(|x| e(&x))?;
    Ok(())
}
