//! `Scene::event_value`, the one event function that event location evaluates (from the
//! part of the model it needs), equals that function in `Scene::event_values` of the full
//! evaluation bit for bit: in the centred and the free scene, at states the nominal grasp
//! reaches (with the contact memories of that moment) and around them.

use crate::common::{bottle, nominal};
use gripopt::eval::{stage_kinematics, stage_statics};
use gripopt::sim::{
    centred_tolerances, drive, free_tolerances, CentredScene, Controls, FreeScene, FreeSetup, Integration, Radau5,
    Scene,
};
use nalgebra::SVector;
use rand::{Rng, SeedableRng};

/// Every watched or not event function of `scene` at `y` and at 20 states around it (each
/// component moved by up to `spread` relative, 1e-6 absolute): the lone value equals the
/// full one bit for bit (NaN equal to NaN), or both are undefined. Returns how many states
/// had a defined model.
fn check_all<const N: usize, const E: usize, Sc: Scene<N, E>>(scene: &Sc, y: &SVector<f64, N>, spread: f64) -> usize {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let mut defined = 0;
    for j in 0..21 {
        let mut yj = *y;
        if j > 0 {
            for v in yj.iter_mut() {
                *v += spread * (v.abs() + 1e-6) * rng.random_range(-1.0..1.0);
            }
        }
        let full = scene.evaluate(&yj).map(|ev| scene.event_values(&yj, &ev));
        defined += usize::from(full.is_some());
        for i in 0..E {
            let lone = scene.event_value(i, &yj);
            match (full, lone) {
                (Some(g), Some(v)) => assert!(
                    g.g[i].to_bits() == v.to_bits() || (g.g[i].is_nan() && v.is_nan()),
                    "event {i} ({:?}) at state {j}: full {} lone {v}",
                    scene.events()[i],
                    g.g[i]
                ),
                // the lone value needs less of the model: it may be defined where the full one is not
                (None, _) => {}
                (Some(g), None) => panic!("event {i} at state {j}: full {} but the lone value undefined", g.g[i]),
            }
        }
    }
    defined
}

#[test]
fn lone_event_values_equal_the_full_evaluations() {
    let p = bottle();
    let s = &p.scene;
    let k = stage_kinematics(&nominal(), s).unwrap();
    let st = stage_statics(&k.finger, s).unwrap();
    let integ = Integration::new(1e-6, 1e-9, 400_000);
    let ctl = Controls::DIAGNOSTIC;
    // before the first contact, just after it, settling, at rest
    for t_mid in [2e-3, 5.3e-3, 8e-3, 20e-3] {
        let mut scene = CentredScene::new(&k.finger, s, &st, &ctl);
        assert!(scene.prepare(st.grasp.f0, &ctl));
        let mut stepper = Radau5::new(centred_tolerances(&integ), integ.h0);
        let run = drive(&mut scene, &mut stepper, &integ, &ctl, t_mid, &mut ());
        assert!((run.t - t_mid).abs() < 1e-12, "centred: reached {}", run.t);
        assert!(check_all(&scene, &run.y, 1e-3) > 15, "centred at {t_mid}");

        let mut free = FreeScene::new(&k.finger, s, st.tau_s0, 0.0, FreeSetup::default());
        let mut stepper = Radau5::new(free_tolerances(&integ), integ.h0);
        let run = drive(&mut free, &mut stepper, &integ, &ctl, t_mid, &mut ());
        assert!((run.t - t_mid).abs() < 1e-12, "free: reached {}", run.t);
        assert!(check_all(&free, &run.y, 1e-4) > 15, "free at {t_mid}");
    }
}
