//! Flexible bodies in simulation: a free beam tumbling in space keeps its linear and
//! angular momentum and its energy, all three computed node by node from the modal data
//! file (not from the engine's inertia invariants).

use mbfmu::dae::{SimOptions, Simulator};
use mbfmu::modal::{BeamSpec, Material, ModalData, Reduction, Section, beam, write};
use std::path::PathBuf;

/// A soft free-free beam, 1 m along x, 8 elements, its first `modes` flexible modes
/// (lowest about 5 Hz): stiff enough to deflect little, soft enough to be excited.
fn soft_beam(modes: usize, clamp: Option<u32>) -> ModalData {
    soft_beam_of(8, modes, clamp)
}

/// [`soft_beam`] with `elements` elements.
fn soft_beam_of(elements: usize, modes: usize, clamp: Option<u32>) -> ModalData {
    let spec = BeamSpec {
        length: 1.0,
        elements,
        section: Section { area: 1e-3, iy: 2e-9, iz: 1e-9, j: 3e-9 },
        material: Material { young: 7e9, shear: 2.7e9, density: 2700.0 },
        modes,
        damping: None,
        clamp,
        reduction: Reduction::FreeInterface,
        shear_coefficient: None,
    };
    beam(&spec).unwrap()
}

/// A directory of its own holding `beam.json`.
fn dir_with(test: &str, data: &ModalData) -> PathBuf {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("flexible-dynamics").join(test);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("beam.json"), write(data)).unwrap();
    dir
}

fn load(dir: &std::path::Path, text: &str) -> mbfmu::model::Model {
    mbfmu::model::load_str(text, &dir.join("m.xml").display().to_string()).unwrap_or_else(|e| panic!("{e}"))
}

/// Linear momentum, angular momentum about the ground origin and total energy (kinetic
/// plus modal strain ½ηᵀKη), node by node: x_i = r + A(s_i + Φt_i η),
/// v_i = v + A(ω' × (s_i + Φt_i η) + Φt_i η̇), spin Ω_i = ω' + Φr_i η̇ (body axes).
fn invariants(s: &Simulator, data: &ModalData) -> ([f64; 3], [f64; 3], f64) {
    let b = s.body_state(0);
    let a = b.rotation;
    let atv = |v: [f64; 3]| -> [f64; 3] { std::array::from_fn(|k| (0..3).map(|i| a[i][k] * v[i]).sum()) };
    let av = |v: [f64; 3]| -> [f64; 3] { std::array::from_fn(|i| (0..3).map(|k| a[i][k] * v[k]).sum()) };
    let cross =
        |x: [f64; 3], y: [f64; 3]| [x[1] * y[2] - x[2] * y[1], x[2] * y[0] - x[0] * y[2], x[0] * y[1] - x[1] * y[0]];
    let w = atv(b.angular_velocity);
    let nm = data.modes.len();
    let (eta, etad) = (&s.q()[6..6 + nm], &s.u()[6..6 + nm]);
    let (mut p, mut h, mut e) = ([0.0; 3], [0.0; 3], 0.0);
    for (i, node) in data.nodes.iter().enumerate() {
        let mut pb = node.position;
        let (mut db, mut spin) = ([0.0; 3], w);
        for k in 0..nm {
            for c in 0..3 {
                pb[c] += data.modes[k][i][c] * eta[k];
                db[c] += data.modes[k][i][c] * etad[k];
                spin[c] += data.modes[k][i][3 + c] * etad[k];
            }
        }
        let apb = av(pb);
        let x: [f64; 3] = std::array::from_fn(|c| b.position[c] + apb[c]);
        let rel = av(std::array::from_fn(|c| cross(w, pb)[c] + db[c]));
        let v: [f64; 3] = std::array::from_fn(|c| b.velocity[c] + rel[c]);
        let js: [f64; 3] = std::array::from_fn(|c| node.inertia[c] * spin[c]);
        let ajs = av(js);
        let xv = cross(x, v);
        for c in 0..3 {
            p[c] += node.mass * v[c];
            h[c] += node.mass * xv[c] + ajs[c];
        }
        e +=
            0.5 * node.mass * v.iter().map(|x| x * x).sum::<f64>() + 0.5 * (0..3).map(|c| spin[c] * js[c]).sum::<f64>();
    }
    let k = data.stiffness_matrix();
    e += 0.5 * (0..nm).map(|r| eta[r] * (0..nm).map(|c| k[r][c] * eta[c]).sum::<f64>()).sum::<f64>();
    (p, h, e)
}

/// A free beam spun about an oblique axis (centrifugal loads excite its modes): over 10 s
/// at tol 1e-12, momenta and energy stay within 1e-8 (relative to their size) of their
/// start values. Radau IIA is not symplectic: its drift is ~tol per unit time, so 1e-8
/// leaves two orders of margin. The engine's own energy (from the invariants) agrees with
/// the node-by-node one to 1e-12.
#[test]
fn a_tumbling_free_beam_conserves_momenta_and_energy() {
    let data = soft_beam(3, None);
    let dir = dir_with("tumbling", &data);
    let m = load(
        &dir,
        r#"<multibody name="tumbling" version="1">
  <flexible_body name="beam" modal="beam.json" position="0.1 0.2 -0.3" euler313="0.3 0.4 0.5"
                 velocity="0.3 -0.2 0.1" angular_velocity="0.5 1.5 2.0"/>
</multibody>
"#,
    );
    let mut s = Simulator::new(&m, SimOptions { tol: 1e-12, max_step: None, ..Default::default() }, 0.0).unwrap();
    let (p0, h0, e0) = invariants(&s, &data);
    let (ps, hs) = (p0.iter().map(|x| x * x).sum::<f64>().sqrt(), h0.iter().map(|x| x * x).sum::<f64>().sqrt());
    let mut worst = [0.0f64; 4];
    let mut eta_max = 0.0f64;
    for k in 1..=100 {
        s.advance(0.1 * f64::from(k)).unwrap_or_else(|e| panic!("{e}"));
        let (p, h, e) = invariants(&s, &data);
        let d = |a: [f64; 3], b: [f64; 3]| (0..3).map(|c| (a[c] - b[c]).abs()).fold(0.0, f64::max);
        worst[0] = worst[0].max(d(p, p0) / ps);
        worst[1] = worst[1].max(d(h, h0) / hs);
        worst[2] = worst[2].max((e - e0).abs() / e0);
        worst[3] = worst[3].max((s.mechanical_energy() - e).abs() / e0);
        eta_max = eta_max.max(s.q()[6..9].iter().fold(0.0, |a: f64, x| a.max(x.abs())));
    }
    eprintln!(
        "tumbling beam: max rel ΔP {:e}, ΔH {:e}, ΔE {:e}, engine vs nodes {:e}; max |η| {eta_max:e}; {:?}",
        worst[0],
        worst[1],
        worst[2],
        worst[3],
        s.stats()
    );
    assert!(eta_max > 1e-6, "the modes must be excited: max |η| = {eta_max:e}");
    assert!(worst[0] < 1e-8 && worst[1] < 1e-8 && worst[2] < 1e-8, "{worst:?}");
    assert!(worst[3] < 1e-12, "{worst:?}");
}

/// A cantilever: the beam's modes computed with node 0 clamped, the body fixed to ground
/// at node 0. Linearized at rest, the states are the modal coordinates and the
/// eigenvalues of A are ±i 2π f_k of the data's frequencies to 1e-10 (relative): the
/// modes are mass-normalized to rounding, so M_ηη = I and K = diag((2πf)²) up to 1e-14.
#[test]
fn a_cantilever_linearizes_to_its_modal_frequencies() {
    let lin = cantilever_frequencies(8, 3);
    assert_eq!(
        lin.states,
        ["beam.eta1", "beam.eta2", "beam.eta3", "der(beam.eta1)", "der(beam.eta2)", "der(beam.eta3)"]
    );
}

/// The same with 50 modes (12 elements): the clamp's equations have 57 variables, so
/// their derivatives are seeded a chunk at a time; the 100 states are the modal
/// coordinates and their rates (tolerances in [`cantilever_frequencies`]).
#[test]
fn a_fifty_mode_cantilever_linearizes_to_its_modal_frequencies() {
    let lin = cantilever_frequencies(12, 50);
    assert_eq!(lin.states.len(), 100);
    assert!(lin.states[..50].iter().enumerate().all(|(k, s)| *s == format!("beam.eta{}", k + 1)), "{:?}", lin.states);
}

/// The cantilever of `modes` modes on `elements` elements, linearized at rest: A's
/// stiffness block is −diag((2πf_k)²) and its eigenvalues are ±i 2πf_k, undamped.
fn cantilever_frequencies(elements: usize, modes: usize) -> mbfmu::linearize::Linearization {
    let data = soft_beam_of(elements, modes, Some(0));
    let dir = dir_with(&format!("cantilever-{modes}"), &data);
    let m = load(
        &dir,
        r#"<multibody name="cantilever" version="1">
  <ground><marker name="wall" position="0.5 0 1" euler313="0.2 0.3 0.1"/></ground>
  <flexible_body name="beam" modal="beam.json" position="0.5 0 1" euler313="0.2 0.3 0.1">
    <marker name="root" node="0"/>
  </flexible_body>
  <joint name="clamp" type="fixed" i="beam.root" j="ground.wall"/>
</multibody>
"#,
    );
    let lin = crate::common::lin_at_start(&m);
    let mut im: Vec<f64> = lin.a.eigenvalues().unwrap().iter().filter(|z| z.im > 0.0).map(|z| z.im).collect();
    im.sort_by(f64::total_cmp);
    let mbfmu::modal::ModalStiffness::Frequencies(f) = &data.stiffness else { panic!("frequencies") };
    assert_eq!(im.len(), modes);
    // A itself is [0 I; −Ω² 0]: its Ω² block equals diag((2πf_k)²) to 1e-10 of the
    // largest. The eigenvalues are then exact to what a backward-stable eigensolver
    // gives: 1e-10 relative plus 10ε‖A‖κ_k absolute, κ_k = (1 + ω_k²)/2ω_k the condition
    // number of the eigenvalues of the 2×2 block [0 1; −ω_k² 0] (‖A‖ ~ ω_max²). With
    // 3 modes that term is below 1e-11; with 50 modes (up to ~2 kHz) it dominates.
    let omega: Vec<f64> = f.iter().map(|f| 2.0 * std::f64::consts::PI * f).collect();
    let norm = omega[modes - 1].powi(2);
    for (r, w) in omega.iter().enumerate() {
        for c in 0..modes {
            let want = if r == c { -w * w } else { 0.0 };
            let got = lin.a[(modes + r, c)];
            assert!((got - want).abs() < 1e-10 * norm, "A[{}, {c}] = {got} vs {want}", modes + r);
        }
    }
    let mut worst = 0.0f64;
    for (w, exact) in im.iter().zip(&omega) {
        worst = worst.max((w - exact).abs() / exact);
        let kappa = (1.0 + exact * exact) / (2.0 * exact);
        let tol = 1e-10 * exact + 10.0 * f64::EPSILON * norm * kappa;
        assert!((w - exact).abs() < tol, "ω = {w} vs 2πf = {exact}");
    }
    eprintln!(
        "cantilever ({modes} modes): frequencies {} .. {} Hz, max relative eigenvalue error {worst:e}",
        f[0],
        f[modes - 1]
    );
    for z in lin.a.eigenvalues().unwrap().iter() {
        assert!(z.re.abs() < 1e-10 * z.im.abs().max(1.0), "undamped: {z:?}");
    }
    lin
}

/// A four-bar whose coupler is the flexible beam (free-free modes, revolutes at its end
/// nodes), driven by gravity, linearized at a moving state (t = 0.2 s) in a user state
/// (the crank angle) plus automatic ones: A against central differences of the engine's
/// own state-space map (`common::state_space`, tests only). h = 1e-6; truncation
/// ~1e-12·|f'''|, round-off ~1e-10 relative: 1e-6 relative to max(1, |entry|).
#[test]
fn a_four_bar_with_a_flexible_coupler_matches_central_differences() {
    four_bar_against_central_differences(3, &["crank", "j2.angle", "j3.angle"]);
}

/// The same with five modes: one modal coordinate joins the states beside the joint
/// angles (a closed loop of redundant planar revolutes whose redundancy the coupler's
/// out-of-plane modes partly lift).
#[test]
fn a_four_bar_with_a_five_mode_coupler_matches_central_differences() {
    four_bar_against_central_differences(5, &["crank", "j2.angle", "j3.angle", "coupler.eta1"]);
}

fn four_bar_against_central_differences(modes: usize, states: &[&str]) {
    use mbfmu::linearize::{linearize, select_states};
    let data = soft_beam(modes, None);
    let dir = dir_with(&format!("fourbar-{modes}"), &data);
    let m = load(
        &dir,
        r#"<multibody name="flexbar" version="1">
  <gravity value="0 -9.81 0"/>
  <ground>
    <marker name="O" position="0 0 0"/>
    <marker name="D" position="1.1 0 0"/>
  </ground>
  <body name="crank" mass="0.5" inertia="0.004 0.0001 0.004" position="0 0.15 0">
    <marker name="base" position="0 -0.15 0"/>
    <marker name="tip" position="0 0.15 0"/>
  </body>
  <flexible_body name="coupler" modal="beam.json" position="0 0.3 0">
    <marker name="a" node="0"/>
    <marker name="mid" node="4"/>
    <marker name="b" node="8"/>
  </flexible_body>
  <body name="rocker" mass="0.6" inertia="0.005 0.0002 0.005" position="1.05 0.15 0">
    <marker name="base" position="0.05 -0.15 0"/>
    <marker name="tip" position="-0.05 0.15 0"/>
  </body>
  <joint name="j1" type="revolute" i="crank.base" j="ground.O"/>
  <joint name="j2" type="revolute" i="coupler.a" j="crank.tip"/>
  <joint name="j3" type="revolute" i="coupler.b" j="rocker.tip"/>
  <joint name="j4" type="revolute" i="rocker.base" j="ground.D"/>
  <output name="mid_y" function="dy(coupler.mid)"/>
  <linearization><state name="crank" function="az(crank.base, ground.O)"/></linearization>
</multibody>
"#,
    );
    let mut sim = Simulator::new(&m, SimOptions { tol: 1e-10, max_step: None, ..Default::default() }, 0.0).unwrap();
    let sel = select_states(sim.system(), sim.q(), 0.0, &sim.inputs()).unwrap();
    assert_eq!(sel.states[0].name, "crank");
    // The coupler's bending adds degrees of freedom to the rigid four-bar's one; Eq. 33
    // prefers joint coordinates, so they show as the relative angles at its ends.
    let names: Vec<&str> = sel.states.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(names, states);
    sim.advance(0.2).unwrap();
    let lin = linearize(&mut sim, &sel, 2).unwrap();
    let (sys, q0, t, v0) = (sim.system().clone(), sim.q().to_vec(), sim.time(), sim.inputs());
    let x0 = lin.x.clone();
    let ns = x0.len();
    let h = 1e-6;
    let mut worst = 0.0f64;
    for j in 0..ns {
        let (mut xp, mut xm) = (x0.clone(), x0.clone());
        xp[j] += h;
        xm[j] -= h;
        let (fp, yp) = crate::common::state_space(&sys, &sel, &q0, t, &xp, &v0);
        let (fm, ym) = crate::common::state_space(&sys, &sel, &q0, t, &xm, &v0);
        for i in 0..ns {
            let want = (fp[i] - fm[i]) / (2.0 * h);
            let err = (lin.a[(i, j)] - want).abs() / want.abs().max(1.0);
            worst = worst.max(err);
            assert!(err < 1e-6, "A[{i},{j}] ({} / {}): {} vs {want}", lin.states[i], lin.states[j], lin.a[(i, j)]);
        }
        let want = (yp[0] - ym[0]) / (2.0 * h);
        assert!((lin.c[(0, j)] - want).abs() < 1e-6 * want.abs().max(1.0), "C[0,{j}]: {} vs {want}", lin.c[(0, j)]);
    }
    eprintln!("flexible four-bar: states {:?}, max relative |A − central differences| {worst:e}", lin.states);
}

/// Static equilibrium (`<analysis static="true"/>`) of a cantilever under gravity: with
/// the frame held by the clamp, the modal rows reduce to K η = Ψᵀ Aᵀ g (Ψ_k = Σ m_i φ_ik),
/// so η_k = Ψ_k·g / (2π f_k)² from the data alone; the engine's Newton solution agrees to
/// 1e-10 relative, and the beam stays at rest (|u| < 1e-9 after 0.5 s).
#[test]
fn a_cantilever_under_gravity_finds_its_static_deflection() {
    let data = soft_beam(3, Some(0));
    let dir = dir_with("static", &data);
    let m = load(
        &dir,
        r#"<multibody name="sag" version="1">
  <gravity value="0 -9.81 0"/>
  <analysis static="true"/>
  <ground><marker name="wall" position="0 0 0"/></ground>
  <flexible_body name="beam" modal="beam.json" position="0 0 0">
    <marker name="root" node="0"/>
  </flexible_body>
  <joint name="clamp" type="fixed" i="beam.root" j="ground.wall"/>
</multibody>
"#,
    );
    let mut s = Simulator::new(&m, SimOptions { tol: 1e-10, max_step: None, ..Default::default() }, 0.0).unwrap();
    let mbfmu::modal::ModalStiffness::Frequencies(f) = &data.stiffness else { panic!("frequencies") };
    let eta = s.q()[6..9].to_vec();
    let want: Vec<f64> = f
        .iter()
        .enumerate()
        .map(|(k, fk)| {
            let psi_g: f64 = data.nodes.iter().enumerate().map(|(i, n)| n.mass * data.modes[k][i][1] * -9.81).sum();
            psi_g / (2.0 * std::f64::consts::PI * fk).powi(2)
        })
        .collect();
    let largest = want.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    assert!(largest > 1e-4, "gravity bends the beam: largest |η| {largest:e}");
    for (k, w) in want.iter().enumerate() {
        assert!((eta[k] - w).abs() <= 1e-10 * largest, "η{} = {} vs {w}", k + 1, eta[k]);
    }
    eprintln!("cantilever sag: η {eta:?}, expected {want:?}");
    s.advance(0.5).unwrap();
    let umax = s.u().iter().fold(0.0f64, |a, x| a.max(x.abs()));
    assert!(umax < 1e-9, "at rest: max |u| = {umax:e}");
}

/// A cantilever started deformed in its first mode (`modal_coordinates`,
/// `modal_velocities`) vibrates in that mode alone: the clamp holds the body frame, the
/// modes are mass-normalized (M_ηη = I) with K diagonal, so η₁(t) = a cos ωt +
/// (b/ω) sin ωt, ω = 2πf₁, exactly, and the other modes stay at zero. The outputs
/// `modal(beam, 1)` and `modal_rate(beam, 1)` follow it over 5 s (4.5 periods) to 1e-7
/// of the amplitude (integrator tolerance 1e-11; its global error over that time is
/// ~1e-9 of the amplitude).
///
/// (A free beam would not do: its bending modes in y and z couple through the rotation
/// about the beam's axis, M_θη ∝ η Σ m φ₁ × φ₂, and the pure mode-1 motion is unstable.)
#[test]
fn a_cantilever_started_in_its_first_mode_vibrates_harmonically() {
    let data = soft_beam(3, Some(0));
    let dir = dir_with("harmonic", &data);
    let (a, b) = (0.02, -0.5);
    let m = load(
        &dir,
        &format!(
            r#"<multibody name="harmonic" version="1">
  <parameter name="a" value="{a}"/>
  <ground><marker name="wall" position="0 0 0" euler313="0.3 0.2 0.1"/></ground>
  <flexible_body name="beam" modal="beam.json" position="0 0 0" euler313="0.3 0.2 0.1"
                 modal_coordinates="a 0 0" modal_velocities="{b} 0 0">
    <marker name="root" node="0"/>
  </flexible_body>
  <joint name="clamp" type="fixed" i="beam.root" j="ground.wall"/>
  <output name="eta1" function="modal(beam, 1)"/>
  <output name="eta1_rate" function="modal_rate(beam, 1)"/>
  <output name="others" function="abs(modal(beam, 2)) + abs(modal(beam, 3))"/>
</multibody>
"#
        ),
    );
    let mbfmu::modal::ModalStiffness::Frequencies(f) = &data.stiffness else { panic!("frequencies") };
    let w = 2.0 * std::f64::consts::PI * f[0];
    let amp = (a * a + (b / w) * (b / w)).sqrt();
    let mut s = Simulator::new(&m, SimOptions { tol: 1e-11, max_step: None, ..Default::default() }, 0.0).unwrap();
    let mut worst = [0.0f64; 3];
    for k in 0..=50 {
        let t = 0.1 * f64::from(k);
        s.advance(t).unwrap_or_else(|e| panic!("{e}"));
        let (eta, rate) = (a * (w * t).cos() + b / w * (w * t).sin(), -a * w * (w * t).sin() + b * (w * t).cos());
        worst[0] = worst[0].max((crate::common::out(&mut s, "eta1") - eta).abs() / amp);
        worst[1] = worst[1].max((crate::common::out(&mut s, "eta1_rate") - rate).abs() / (amp * w));
        worst[2] = worst[2].max(crate::common::out(&mut s, "others") / amp);
    }
    eprintln!("harmonic cantilever: f1 = {} Hz, worst η, η̇, other modes (relative) {worst:?}", f[0]);
    assert!(worst.iter().all(|&x| x < 1e-7), "{worst:?}");
}

/// User linearization states may be modal coordinates or node deflections: the
/// cantilever linearized in `2 * modal(beam, 2)`, or in its tip node's lateral deflection
/// relative to the clamped root (`dz(beam.tip, beam.root, beam.root)`), plus automatic
/// states for the rest, has the same eigenvalues as in the automatic selection,
/// ±i 2πf_k to 1e-10 relative (as above).
#[test]
fn a_cantilever_linearizes_in_a_modal_or_node_deflection_user_state() {
    let data = soft_beam(3, Some(0));
    let dir = dir_with("cantilever-user", &data);
    let tip = data.nodes[data.nodes.len() - 1].id;
    let mbfmu::modal::ModalStiffness::Frequencies(f) = &data.stiffness else { panic!("frequencies") };
    for state in ["2 * modal(beam, 2)", "dz(beam.tip, beam.root, beam.root)"] {
        let m = load(
            &dir,
            &format!(
                r#"<multibody name="cantilever" version="1">
  <ground><marker name="wall" position="0 0 0"/></ground>
  <flexible_body name="beam" modal="beam.json" position="0 0 0">
    <marker name="root" node="0"/>
    <marker name="tip" node="{tip}"/>
  </flexible_body>
  <joint name="clamp" type="fixed" i="beam.root" j="ground.wall"/>
  <linearization><state name="mine" function="{state}"/></linearization>
</multibody>
"#
            ),
        );
        let lin = crate::common::lin_at_start(&m);
        assert_eq!((lin.states[0].as_str(), lin.states.len()), ("mine", 6), "{state}: {:?}", lin.states);
        let mut im: Vec<f64> = lin.a.eigenvalues().unwrap().iter().filter(|z| z.im > 0.0).map(|z| z.im).collect();
        im.sort_by(f64::total_cmp);
        assert_eq!(im.len(), 3, "{state}");
        for (w, f) in im.iter().zip(f) {
            let exact = 2.0 * std::f64::consts::PI * f;
            assert!((w - exact).abs() < 1e-10 * exact, "{state}: ω = {w} vs 2πf = {exact}");
        }
    }
}

/// A force at a node marker bends the body: a cantilever pushed at its tip node by a
/// ground-fixed force F (no gravity) settles, in static equilibrium, at
/// η_k = φ_k,tip·F / (2πf_k)² from the data alone (the clamp holds the frame, M_ηη = I,
/// K diagonal); the engine agrees to 1e-10 relative to the largest |η|.
#[test]
fn a_cantilever_pushed_at_its_tip_node_deflects_as_its_modes_predict() {
    let data = soft_beam(3, Some(0));
    let dir = dir_with("tip-force", &data);
    let tip = data.nodes.len() - 1;
    let f = [0.02, -0.05, 0.03];
    let m = load(
        &dir,
        &format!(
            r#"<multibody name="pushed" version="1">
  <analysis static="true"/>
  <ground><marker name="wall" position="0 0 0"/></ground>
  <flexible_body name="beam" modal="beam.json" position="0 0 0">
    <marker name="root" node="0"/>
    <marker name="tip" node="{}" euler313="0.4 0.3 0.2"/>
  </flexible_body>
  <joint name="clamp" type="fixed" i="beam.root" j="ground.wall"/>
  <gforce name="push" i="beam.tip" force="{} {} {}"/>
</multibody>
"#,
            data.nodes[tip].id, f[0], f[1], f[2]
        ),
    );
    let s = Simulator::new(&m, SimOptions { tol: 1e-10, max_step: None, ..Default::default() }, 0.0).unwrap();
    let mbfmu::modal::ModalStiffness::Frequencies(fr) = &data.stiffness else { panic!("frequencies") };
    let want: Vec<f64> = (0..3)
        .map(|k| {
            let work: f64 = (0..3).map(|c| data.modes[k][tip][c] * f[c]).sum();
            work / (2.0 * std::f64::consts::PI * fr[k]).powi(2)
        })
        .collect();
    let largest = want.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    assert!(largest > 1e-4, "the force bends the beam: largest |η| {largest:e}");
    let eta = &s.q()[6..9];
    for (k, w) in want.iter().enumerate() {
        assert!((eta[k] - w).abs() <= 1e-10 * largest, "η{} = {} vs {w}", k + 1, eta[k]);
    }
}

/// A rigid ball tied by a spring (no damping) to the tip node of a free beam, in space:
/// the spring's reaction loads the beam through its tip node, so it does work on the
/// modes. Over 2 s at tol 1e-12 linear momentum and total energy (kinetic, modal strain,
/// spring) stay within 1e-7 and 1e-6 (relative; measured 3e-8 and 7e-8 over 5 s: the
/// stiff, irregular motion makes Radau's drift larger than for the tumbling beam), and
/// the modes are excited to |η| > 1e-4. Without the modal part of node loads the modes
/// stay near 1e-6 and the energy drifts by 5e-5.
#[test]
fn a_spring_on_a_node_marker_does_the_work_its_modes_store() {
    let data = soft_beam(3, None);
    let dir = dir_with("node-spring", &data);
    let tip = data.nodes[data.nodes.len() - 1].id;
    let m = load(
        &dir,
        &format!(
            r#"<multibody name="tied" version="1">
  <flexible_body name="beam" modal="beam.json" position="0 0 0" angular_velocity="0.2 0.3 -0.1">
    <marker name="tip" node="{tip}"/>
  </flexible_body>
  <body name="ball" mass="0.5" inertia="1e-3 1e-3 1e-3" position="1.1 0.2 -0.1" velocity="0.5 -1 2"/>
  <spring_damper name="tie" type="translational" i="ball.cm" j="beam.tip" stiffness="400" damping="0" length="0.1"/>
</multibody>
"#
        ),
    );
    let mut s = Simulator::new(&m, SimOptions { tol: 1e-12, max_step: None, ..Default::default() }, 0.0).unwrap();
    let momentum = |s: &Simulator| -> [f64; 3] {
        let (b, n) = (s.body_state(1), invariants(s, &data).0);
        std::array::from_fn(|c| n[c] + 0.5 * b.velocity[c])
    };
    let (p0, e0) = (momentum(&s), s.mechanical_energy());
    let ps = p0.iter().map(|x| x * x).sum::<f64>().sqrt();
    let (mut worst_p, mut worst_e, mut eta_max) = (0.0f64, 0.0f64, 0.0f64);
    for k in 1..=20 {
        s.advance(0.1 * f64::from(k)).unwrap_or_else(|e| panic!("{e}"));
        let p = momentum(&s);
        worst_p = worst_p.max((0..3).map(|c| (p[c] - p0[c]).abs()).fold(0.0, f64::max) / ps);
        worst_e = worst_e.max((s.mechanical_energy() - e0).abs() / e0);
        eta_max = eta_max.max(s.q()[12..15].iter().fold(0.0, |a: f64, x| a.max(x.abs())));
    }
    eprintln!("ball on a beam's tip node: max rel ΔP {worst_p:e}, ΔE {worst_e:e}; max |η| {eta_max:e}");
    assert!(eta_max > 1e-4, "the spring must bend the beam: max |η| = {eta_max:e}");
    assert!(worst_p < 1e-7 && worst_e < 1e-6, "ΔP {worst_p:e}, ΔE {worst_e:e}");
}

/// The example `models/flexible/suspension.xml` (double wishbone, flexible lower arm with
/// 8 Craig–Bampton modes): 22 constraints on 32 coordinates leave 10 degrees of freedom,
/// all of them linearization states at its static equilibrium (the state selection scales
/// the modal columns, without which a rank decision dropped below the true rank here);
/// every mode is damped (Re λ < 0) and comes as a complex pair: body bounce, wheel hop,
/// the fore-aft compliance mode of the wheel on the arm, the arm's own modes.
#[test]
fn the_suspension_example_linearizes_in_ten_degrees_of_freedom() {
    let path = crate::common::model_dir().join("flexible/suspension.xml");
    let m = mbfmu::model::load_file(&path).unwrap_or_else(|e| panic!("{e}"));
    let lin = crate::common::lin_at_start(&m);
    assert_eq!(lin.states.len(), 20, "{:?}", lin.states);
    assert_eq!(&lin.states[..2], ["z_body", "z_wheel"]);
    let ev = lin.a.eigenvalues().unwrap();
    assert!(ev.iter().all(|z| z.re < 0.0), "{ev:?}");
    assert_eq!(ev.iter().filter(|z| z.im > 0.0).count(), 10, "{ev:?}");
}

/// Output derivatives (`fmi2GetRealOutputDerivatives`) of a flexible model: a free beam
/// on a revolute joint under gravity, started bent in its first two modes, with outputs
/// of a node's position and velocity and of modal coordinates and rates; each d/dt at
/// t = 1 equals the central difference of the outputs (tolerances of
/// `state::output_derivatives_match_differences`). Before the modal rates were part of
/// q̇ there, the modal coordinates were dropped from the evaluation.
#[test]
fn output_derivatives_of_a_flexible_pendulum_match_differences_of_the_outputs() {
    let data = soft_beam(3, None);
    let dir = dir_with("output-derivatives", &data);
    let tip = data.nodes[data.nodes.len() - 1].id;
    let m = load(
        &dir,
        &format!(
            r#"<multibody name="swing" version="1">
  <gravity value="0 0 -9.81"/>
  <ground><marker name="pivot" position="0 0 0" euler313="0 1.5707963267948966 0"/></ground>
  <flexible_body name="beam" modal="beam.json" position="0 0 0" modal_coordinates="0.01 -0.005 0">
    <marker name="root" node="0" euler313="0 1.5707963267948966 0"/>
    <marker name="tip" node="{tip}"/>
  </flexible_body>
  <joint name="hinge" type="revolute" i="beam.root" j="ground.pivot"/>
  <output name="tip_z" function="dz(beam.tip)"/>
  <output name="tip_vy" function="vy(beam.tip)"/>
  <output name="eta2" function="modal(beam, 2)"/>
  <output name="eta1_rate" function="modal_rate(beam, 1)"/>
</multibody>
"#
        ),
    );
    crate::state::output_derivatives_match_differences(&m, &[]);
}
