//! An algebraic loop through a constraint force: a pendulum whose pin friction torque is
//! proportional to the pin's reaction force, μ r |F| tanh(ω/ε) (Coulomb-like, smoothed).
//! The reaction depends on the acceleration, which depends on the friction torque: solved
//! with the equations of motion (Newton, exact Jacobian through the load's derivatives).

use crate::common;
use mbfmu::dae::{SimOptions, Simulator};
use mbfmu::linearize::{linearize, select_states};
use mbfmu::model::parse::load_str;

/// tests/models/pin_friction.xml (outputs: angle, normal, torque, omega).
const MODEL: &str = include_str!("../models/pin_friction.xml");

#[test]
fn pin_friction_loop_dissipates_and_its_torque_follows_the_reaction() {
    // The friction torque (about the hinge axis = ground y) equals −μ r |F_pin| tanh(ω/ε)
    // at every output time (to 1e-9: the loop is solved, not lagged); energy decreases
    // monotonically; |C| < tol.
    let m = load_str(MODEL, "pin.xml").unwrap();
    let mut sim = Simulator::new(&m, SimOptions { tol: 1e-9, max_step: None, ..Default::default() }, 0.0).unwrap();
    let mut e_prev = sim.mechanical_energy();
    for k in 1..=40 {
        sim.advance(0.05 * k as f64).unwrap();
        let y = sim.outputs().unwrap();
        let w = sim.body_state(0).angular_velocity[1];
        let want = -0.3 * 0.05 * (y[1] * y[1] + 1e-6).sqrt() * (w / 0.05).tanh();
        assert!((y[2] - want).abs() < 1e-9 * (1.0 + want.abs()), "t = {}: {} vs {want}", sim.time(), y[2]);
        let e = sim.mechanical_energy();
        assert!(e <= e_prev + 1e-9, "energy rose at t = {}: {e} > {e_prev}", sim.time());
        e_prev = e;
        assert!(sim.constraint_residual() < 1e-9);
    }
}

#[test]
fn pin_friction_linearization_matches_central_differences_of_the_state_space_map() {
    // A (states θ-like internal coordinate and its rate) and C (angle, normal force,
    // friction torque) at a moving state (t = 0.3) against central differences of the
    // engine's own state-space map with the loop solved (tests/common), 1e-6 relative.
    let m = load_str(MODEL, "pin.xml").unwrap();
    let mut sim = Simulator::new(&m, SimOptions { tol: 1e-10, max_step: None, ..Default::default() }, 0.0).unwrap();
    let sel = select_states(sim.system(), sim.q(), 0.0, &sim.inputs()).unwrap();
    sim.advance(0.3).unwrap();
    let lin = linearize(&mut sim, &sel, 2).unwrap();
    let (sys, q0, t) = (sim.system().clone(), sim.q().to_vec(), sim.time());
    let x0 = lin.x.clone();
    let ns = x0.len();
    assert_eq!(ns, 2);
    let v: Vec<f64> = vec![];
    for c in 0..ns {
        let h = 1e-6 * x0[c].abs().max(1.0);
        let (mut xp, mut xm) = (x0.clone(), x0.clone());
        xp[c] += h;
        xm[c] -= h;
        let (fp, yp) = common::state_space(&sys, &sel, &q0, t, &xp, &v);
        let (fm, ym) = common::state_space(&sys, &sel, &q0, t, &xm, &v);
        for r in 0..ns {
            let fd = (fp[r] - fm[r]) / (2.0 * h);
            let e = (fd - lin.a[(r, c)]).abs() / lin.a[(r, c)].abs().max(1.0);
            assert!(e < 1e-6, "A[{r},{c}] = {} vs fd {fd}", lin.a[(r, c)]);
        }
        for r in 0..yp.len() {
            let fd = (yp[r] - ym[r]) / (2.0 * h);
            let e = (fd - lin.c[(r, c)]).abs() / lin.c[(r, c)].abs().max(1.0);
            assert!(e < 1e-6, "C[{r},{c}] = {} vs fd {fd}", lin.c[(r, c)]);
        }
    }
    // The loop matters: without friction the rate row differs.
    assert!(lin.a[(1, 1)].abs() > 1e-3, "friction damping visible in A: {}", lin.a[(1, 1)]);
}
