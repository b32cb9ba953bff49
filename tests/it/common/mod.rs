//! Helpers shared by the integration tests: where the crate's files are, the `mbfmu`
//! binary, the engine's outputs and linearization, and the engine's state-space map as an
//! independent reference for A, B, C, D. `host` is a host of the FMU's C API.

pub mod host;

use faer::linalg::solvers::Solve;
use mbfmu::dae::init::consistent_accelerations;
use mbfmu::dae::radau::Stats;
use mbfmu::dae::sparse::SparseLu;
use mbfmu::dae::{SimOptions, Simulator};
use mbfmu::fmi::types::Component;
use mbfmu::linearize::jets::{PositionFn, jets};
use mbfmu::linearize::{Linearization, Selection, linearize, select_states};
use mbfmu::mechanics::System;
use mbfmu::mechanics::constraint_jacobian::IndependentRows;
use mbfmu::mechanics::coords::local_columns;
use mbfmu::mechanics::loads::{load_index, load_value};
use mbfmu::mechanics::local::LocalCtx;
use mbfmu::model::Model;
use mbfmu::model::expr::{ElementRef, LoadFn};
use mbfmu::model::parse::load_file;
use std::path::PathBuf;
use std::process::{Command, Output, Stdio};

/// Every example model ([`model_files`]) in motion: simulated at tolerance 1e-10 from its
/// experiment start for 0.05 s, with its path (the points the linearization route tests
/// compare at).
pub fn moving_examples() -> impl Iterator<Item = (PathBuf, Simulator)> {
    model_files().into_iter().map(|path| {
        let model = load_file(&path).unwrap_or_else(|e| panic!("{e}"));
        let t0 = model.experiment.start.unwrap_or(0.0);
        let opts = SimOptions { tol: 1e-10, max_step: None, ..Default::default() };
        let mut sim = Simulator::new(&model, opts, t0).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        sim.advance(t0 + 0.05).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        (path, sim)
    })
}

/// The crate's root directory.
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The example models' directory, `models/`.
pub fn model_dir() -> PathBuf {
    root().join("models")
}

/// Every example model file, `models/*.xml` then `models/flexible/*.xml`, each sorted.
/// The flexible ones read modal data files beside them: load them by path
/// ([`load_file`], [`guid_of`], `host::resources_of`), not from their text alone.
pub fn model_files() -> Vec<PathBuf> {
    let mut v = xml_files(&model_dir());
    v.extend(flexible_model_files());
    v
}

/// The example models with flexible bodies, `models/flexible/*.xml`, sorted.
pub fn flexible_model_files() -> Vec<PathBuf> {
    xml_files(&model_dir().join("flexible"))
}

/// The `*.xml` files of `dir`, sorted.
fn xml_files(dir: &std::path::Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.expect("readable directory entry").path())
        .filter(|p| p.extension().is_some_and(|x| x == "xml"))
        .collect();
    v.sort();
    v
}

/// The text of the example model `models/<name>`.
pub fn model_text(name: &str) -> String {
    std::fs::read_to_string(model_dir().join(name)).unwrap()
}

/// The example model `models/<name>`, loaded.
pub fn model(name: &str) -> Model {
    load_file(&model_dir().join(name)).unwrap_or_else(|e| panic!("{e}"))
}

/// The GUID `mbfmu pack` gives the FMU of the model text `text` (one that does not load
/// has none: a placeholder, which instantiation refuses with the model's error).
pub fn guid(text: &str) -> String {
    match mbfmu::model::parse::load_str(text, "model.xml") {
        Ok(m) => mbfmu::fmi::guid::guid(&m, text),
        Err(_) => "{not a model}".to_string(),
    }
}

/// The GUID `mbfmu pack` gives the FMU of the model file `path` (its modal data files
/// read from beside it).
pub fn guid_of(path: &std::path::Path) -> String {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    mbfmu::fmi::guid::guid(&load_file(path).unwrap_or_else(|e| panic!("{e}")), &text)
}

/// Run the `mbfmu` binary with `args` in the crate's root, without stdin.
pub fn mbfmu(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mbfmu"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdin(Stdio::null())
        .output()
        .expect("the mbfmu binary runs")
}

/// The integrator statistics of the engine of FMU instance `c` and the instance's step
/// limit (solver.maxSteps), read behind the C API (through the handle registry, as every
/// export enters an instance), so that a test can bound the work a call did by counting it
/// instead of timing it. None when `c` is not a live instance, is busy, or has no engine.
pub fn engine_stats(c: Component) -> Option<(Stats, usize)> {
    let mut session = mbfmu::fmi::handle::enter(c).ok()?;
    let inst = session.instance();
    let limit = inst.config.max_steps;
    inst.built.as_ref().map(|b| (b.sim.stats(), limit))
}

/// Integrator step attempts made between two [`engine_stats`] readings of one instance
/// (when the engine was rebuilt in between, its new count is all made since).
pub fn attempts_between(before: Option<(Stats, usize)>, after: Option<(Stats, usize)>) -> usize {
    match (before, after) {
        (Some((b, _)), Some((a, _))) if a.steps >= b.steps => a.steps - b.steps,
        (_, Some((a, _))) => a.steps,
        (_, None) => 0,
    }
}

/// The current value of output `name`.
pub fn out(s: &mut Simulator, name: &str) -> f64 {
    let i = s.output_names().iter().position(|n| n == name).unwrap_or_else(|| panic!("no output {name}"));
    s.outputs().unwrap()[i]
}

/// The linearization of `m` at t = 0 (tolerance 1e-10, automatic states).
pub fn lin_at_start(m: &Model) -> Linearization {
    let mut sim = Simulator::new(m, SimOptions { tol: 1e-10, max_step: None, ..Default::default() }, 0.0).unwrap();
    let sel = select_states(sim.system(), sim.q(), 0.0, &sim.inputs()).unwrap();
    linearize(&mut sim, &sel, 2).unwrap()
}

/// The engine's state-space map x = (S, W), v ↦ (Ṡ, Ẇ, y) at time t: q from C(q) = 0,
/// s(q) = S by Newton (from `q0`); u from P u + C_t = 0, ṡ(q, u) = W; u̇ and λ from the
/// equations of motion (an algebraic loop through element loads solved by fixed point);
/// the outputs y from (q, u, u̇) and the element loads from (q, u, λ). Models without
/// differential states only (user variables are solved, not states).
/// Central differences of this map are the tests' independent reference for A, B, C, D.
pub fn state_space(sys: &System, sel: &Selection, q0: &[f64], t: f64, x: &[f64], v: &[f64]) -> (Vec<f64>, Vec<f64>) {
    // Constraint rows found redundant at initialization are left out (their λ = 0).
    let rows = IndependentRows::of(sys);
    let (n, m, s) = (sys.n(), rows.count, sel.states.len());
    let zeros = vec![0.0; n];
    let mut q = q0.to_vec();
    let square = |q: &[f64], u: &[f64], level: usize| -> (Vec<f64>, Vec<f64>) {
        // Rows: constraints (level 0: C, level 1: Ċ), then states (s or ṡ); columns: q or u.
        let mut mat = vec![0.0; n * n];
        let mut r = vec![0.0; n];
        for el in &sys.constraints {
            let js = jets(sys, el, q, u, &zeros, t, v);
            for (e, j) in js.iter().enumerate() {
                let Some(row) = rows.of_row[el.row + e] else { continue };
                r[row] = if level == 0 { j.g } else { j.g1 };
                let g = if level == 0 { &j.dg } else { &j.dg1 };
                let cols = local_columns(sys, el.bodies());
                let nql = cols.len();
                for (a, &c) in cols.iter().enumerate() {
                    mat[row * n + c] += g[if level == 0 { a } else { nql + a }];
                }
            }
        }
        for (k, st) in sel.states.iter().enumerate() {
            let j = &jets(sys, st, q, u, &zeros, t, v)[0];
            r[m + k] = if level == 0 { j.g - x[k] } else { j.g1 - x[s + k] };
            let g = if level == 0 { &j.dg } else { &j.dg1 };
            let cols = local_columns(sys, st.bodies());
            let nql = cols.len();
            for (a, &c) in cols.iter().enumerate() {
                mat[(m + k) * n + c] += g[if level == 0 { a } else { nql + a }];
            }
        }
        (mat, r)
    };
    let solve = |mat: &[f64], r: &[f64]| -> Vec<f64> {
        let a = faer::Mat::from_fn(n, n, |i, j| mat[i * n + j]);
        let b = faer::Mat::from_fn(n, 1, |i, _| r[i]);
        let sol = a.full_piv_lu().solve(&b);
        (0..n).map(|i| sol[(i, 0)]).collect()
    };
    for _ in 0..30 {
        let (mat, r) = square(&q, &zeros, 0);
        let dq = solve(&mat, &r);
        for i in 0..n {
            q[i] -= dq[i];
        }
        if dq.iter().all(|d| d.abs() < 1e-15) {
            break;
        }
    }
    // ṡ and Ċ are affine in u: residual at u = 0, matrix = their u-gradients.
    let (mat, r) = square(&q, &zeros, 1);
    let u: Vec<f64> = solve(&mat, &r).iter().map(|x| -x).collect();
    // Accelerations and multipliers (with any algebraic loop through element loads solved).
    let mut z = vec![0.0; sys.nz()];
    let (udot, lam) = consistent_accelerations(sys, &q, &u, t, v, &mut z, &mut SparseLu::new()).unwrap();
    let mut xd = x[s..].to_vec();
    for st in &sel.states {
        xd.push(jets(sys, st, &q, &u, &udot, t, v)[0].g2);
    }
    let ids: Vec<usize> = (0..sys.nb()).collect();
    let ext = sys.ext(v, &z, Some((&q, &u, &lam)), t);
    let loads =
        |f: LoadFn, e: ElementRef| load_value(sys, e, (&q, &u, &lam), t, &ext).map_or(f64::NAN, |l| l[load_index(f)]);
    let mut ctx = LocalCtx::new(sys, &ids, &q, &u, &udot, t, &ext);
    ctx.loads = Some(&loads);
    let y = sys.outputs.iter().zip(&sys.output_bases).map(|(e, &b)| ctx.eval_expr(e, b)).collect();
    (xd, y)
}
