//! Stage-1/2 boundary cases (MODEL.md §7, §10, §13 items 1, 2).
use crate::common::*;
use gripopt::eval::{evaluate, Discard, EvalOptions, Reason};
use gripopt::math::dist_to_singular;
use gripopt::model::Finger;
use gripopt::model::{singularity_sweep, SweepFailure};
use gripopt::params::Design;

fn margin_deg(x: &Design) -> Option<f64> {
    let s = scene();
    let f = Finger::new(x, &s).ok()?;
    match singularity_sweep(&f, &s) {
        Ok(sw) => Some(sw.min_margin.to_degrees()),
        Err(SweepFailure::Margin(sw)) => Some(sw.min_margin.to_degrees()),
        Err(_) => None,
    }
}

/// Why statics discard `x` in the nominal scene (it must be discarded).
#[track_caller]
fn statics_discard(x: &Design) -> Discard {
    evaluate(x, &scene(), &EvalOptions::statics_only()).discard.unwrap_or_else(|| panic!("{x:?} passes statics"))
}

#[test]
fn designs_just_inside_and_outside_the_30_degree_margin() {
    // walk ψ down from the nominal (margin 33.9°) to bracket the 30° crossing
    let base = nominal();
    let with_psi = |d: f64| Design { psi: d.to_radians(), ..base };
    let mut prev = 129.76;
    let mut bracket = None;
    for step in 1..400 {
        let cand = 129.76 - 0.1 * step as f64;
        match margin_deg(&with_psi(cand)) {
            Some(m) if m < 30.0 => {
                bracket = Some((prev, cand));
                break;
            }
            Some(_) => prev = cand,
            None => break,
        }
    }
    let (above, below) = bracket.expect("no ψ below the nominal crosses the 30° margin");
    // bisect the 30° boundary; the two ends of the final bracket sit just inside and just
    // outside (the margin is a minimum over the sweep grid, so it may step slightly)
    let (mut a, mut b) = (above, below);
    for _ in 0..80 {
        let mid = 0.5 * (a + b);
        if margin_deg(&with_psi(mid)).unwrap() >= 30.0 {
            a = mid
        } else {
            b = mid
        }
    }
    let s = scene();
    let opts = EvalOptions::statics_only();
    let (inside, outside) = (with_psi(a), with_psi(b));
    let mi = margin_deg(&inside).unwrap();
    let mo = margin_deg(&outside).unwrap();
    assert!((30.0..30.1).contains(&mi), "inside margin {mi}");
    assert!(mo < 30.0 && mo > 29.9, "outside margin {mo}");
    let ei = evaluate(&inside, &s, &opts);
    assert!(ei.discard.is_none_or(|d| d.stage > 1), "inside discarded at stage 1: {:?}", ei.discard);
    let eo = evaluate(&outside, &s, &opts);
    let d = eo.discard.expect("outside must be discarded");
    assert_eq!(d.stage, 1);
    assert!(matches!(d.reason, Reason::Sweep(SweepFailure::Margin(_))), "{}", d.reason);
    assert!(d.reason.to_string().contains("singularity margin"));
    assert!((d.violation - (30.0 - mo)).abs() < 1e-9, "violation {} vs {}", d.violation, 30.0 - mo);
    // independent check of the margin at the open pose, where the nominal family attains it
    let f = Finger::new(&outside, &s).unwrap();
    let open_margin =
        [f.open.q12, f.open.q22, f.open.q13].iter().map(|a| dist_to_singular(*a)).fold(f64::INFINITY, f64::min);
    assert!(open_margin.to_degrees() >= mo - 1e-9);
}

#[test]
fn open_pose_undefined_for_a_short_palm() {
    // k10² = (b/2)² + R_open² − (R_open + w)² ≤ 0 for b ≤ 2 sqrt(0.055² − 0.05²) = 45.8 mm
    let d = statics_discard(&Design { b: 0.045, ..nominal() });
    assert_eq!(d.stage, 1);
    assert!(d.reason.to_string().contains("k10"), "{}", d.reason);
    let x = Design { b: 0.0459, ..nominal() };
    assert!(Finger::new(&x, &scene()).is_ok());
}

#[test]
fn invalid_lengths_are_stage_0() {
    for x in [
        Design { l21: -0.01, ..nominal() },
        Design { t22: 0.0, ..nominal() },
        Design { p: 0.0, ..nominal() },
        Design { r: f64::NAN, ..nominal() },
    ] {
        let d = statics_discard(&x);
        assert_eq!(d.stage, 0);
        assert_eq!(d.reason, Reason::InvalidDesign);
    }
}

#[test]
fn distal_contact_beyond_tip_is_stage_2() {
    // nominal k2 = 30.45 mm on R = 40 mm: a distal of 30.4 mm is just too short, 30.5 mm fits
    let d = statics_discard(&Design { t22: 0.0304, ..nominal() });
    assert_eq!(d.stage, 2, "{}", d.reason);
    assert!(d.reason.to_string().contains("k2 > t22"), "{}", d.reason);
    let ok = Design { t22: 0.0305, ..nominal() };
    let ev = evaluate(&ok, &scene(), &EvalOptions::statics_only());
    assert!(ev.statics.is_some(), "{:?}", ev.discard);
}

#[test]
fn proximal_contact_beyond_the_proximal_phalanx() {
    // k1 = 18.95 mm for the nominal base: a proximal phalanx of 18 mm cannot reach the tangent point
    let d = statics_discard(&Design { l21: 0.018, ..nominal() });
    assert!(d.stage == 1 || d.stage == 2);
    assert!(d.reason.to_string().contains("k1") || d.reason.to_string().contains("R = "), "{}", d.reason);
}

#[test]
fn unmountable_linkage() {
    // a transmission ratio so large that link 22 cannot be closed by bar 12 along the sweep
    let s = scene();
    let mut saw = false;
    for r in [3.0, 5.0, 8.0] {
        for p in [1.2, 1.5, 2.0] {
            let x = Design { r, p, ..nominal() };
            if let Some(d) = evaluate(&x, &s, &EvalOptions::statics_only()).discard {
                if d.stage == 1
                    && (d.reason.to_string().contains("mountable") || d.reason.to_string().contains("assembly"))
                {
                    saw = true;
                    assert_eq!(d.violation, 90.0);
                }
            }
        }
    }
    assert!(saw, "no unmountable design found");
}
