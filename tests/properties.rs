//! Property tests over random designs inside and around the bounds (full pipeline).
use gripopt::eval::{evaluate, EvalOptions, Evaluation, Record};
use gripopt::params::Design;
use gripopt::sim::DynOutcome;
use proptest::prelude::*;

fn check_finite(ev: &Evaluation) -> Result<(), String> {
    let bad = |name: &str, v: f64| if v.is_finite() { Ok(()) } else { Err(format!("{name} = {v}")) };
    if let Some(k) = &ev.kin {
        let f = &k.finger;
        for (n, v) in [
            ("l11", f.l11),
            ("l12", f.l12),
            ("l22", f.l22),
            ("q11_0", f.open.q11),
            ("q12_0", f.open.q12),
            ("q13_0", f.open.q13),
            ("margin", k.sweep.min_margin),
        ] {
            bad(n, v)?;
        }
        for v in f.mass.m.iter().chain(f.mass.i.iter()) {
            bad("mass", *v)?;
        }
    }
    if let Some(s) = &ev.statics {
        let g = &s.grasp;
        let grasp = [g.theta, g.k, g.f0, g.fmu, g.hand0, g.hand_mu].into_iter().flatten();
        for v in [s.tau_s0, s.max_offset, s.alpha, s.mean_force].into_iter().chain(grasp) {
            bad("statics", v)?;
        }
    }
    if let Some(d) = &ev.dynamics {
        if let Some(fc) = &d.first {
            for v in [fc.t, fc.theta2, fc.impact.e_cyl, fc.impact.m_finger, fc.impact.v_impact, fc.impact.e_lim] {
                bad("first contact", v)?;
            }
        }
        if let Some(t) = d.t_stab {
            bad("t_stab", t)?;
        }
        bad("f_end", d.f_end[0])?;
        bad("f_end", d.f_end[1])?;
        bad("t_end", d.t_end)?;
        let early = matches!(
            d.outcome,
            DynOutcome::NoEquilibrium | DynOutcome::StaticForceLimit | DynOutcome::InitialPenetration
        );
        if !early {
            bad("v_star", d.v_star)?;
            bad("fstar", d.fstar[0])?;
            bad("e_ex_end", d.e_ex_end)?;
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, ..ProptestConfig::default() })]

    #[test]
    fn pipeline_never_panics_nor_produces_nan(
        u in proptest::array::uniform6(-0.3f64..1.3),
    ) {
        let p = crate::common::bottle();
        // inside and ±30 % around the box
        let mut x = [0.0; 6];
        for i in 0..6 {
            x[i] = p.bounds.lo[i] + u[i] * (p.bounds.hi[i] - p.bounds.lo[i]);
        }
        let design = Design::from_array(&x);
        let ev = evaluate(&design, &p.scene, &EvalOptions::full(&p));
        prop_assert!(check_finite(&ev).is_ok(), "{:?}", check_finite(&ev));
        if let Some(d) = ev.discard {
            prop_assert!(d.stage <= 3);
            prop_assert!(!d.reason.to_string().is_empty());
            prop_assert!(d.violation.is_finite() && d.violation >= 0.0, "violation {}", d.violation);
        } else {
            let o = ev.objectives();
            prop_assert!(o.iter().all(|v| v.is_finite()));
        }
        let r = Record::from_eval(&ev);
        prop_assert_eq!(r.verdict.feasible, ev.discard.is_none());
        prop_assert_eq!(r.verdict.failed_stage.is_some(), r.verdict.reason.is_some());
        let json = serde_json::to_string(&r).unwrap();
        prop_assert!(!json.contains("NaN") && !json.contains("inf"));
    }

    #[test]
    fn degenerate_values_are_stage_0(bad in prop_oneof![Just(0.0), Just(-1e-3), Just(f64::NAN), Just(f64::INFINITY)], which in 0usize..5) {
        let p = crate::common::bottle();
        let mut x = p.nominal.to_array();
        x[which] = bad;
        let ev = evaluate(&Design::from_array(&x), &p.scene, &EvalOptions::full(&p));
        let d = ev.discard.unwrap();
        prop_assert_eq!(d.stage, 0);
    }
}
