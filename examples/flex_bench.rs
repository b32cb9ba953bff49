//! Flexible-body benchmark (issue 14): simulation and linearization time of a free beam
//! tumbling in space and of a cantilever under gravity, for 5, 20 and 50 modes, and of
//! the example `models/flexible/suspension.xml` (its lower arm with 6, 20 and 50
//! Craig–Bampton modes: six is the fewest its two joint nodes give), each with 20 vs
//! 200 beam elements. After the inertia invariants are computed the node count must not
//! matter: the 200/20 ratios should be ≈ 1 (the generator's eigen solve, timed apart,
//! does grow with it).
//! Usage: cargo run --release --example flex_bench   (bench/flexible.sh runs it)

use mbfmu::dae::{SimOptions, Simulator};
use mbfmu::linearize::{linearize, select_states};
use mbfmu::modal::{BeamSpec, Material, Reduction, Section, beam, write};
use std::time::Instant;

const TUMBLING: &str = r#"<multibody name="tumbling" version="1">
  <flexible_body name="beam" modal="beam.json" position="0 0 0" angular_velocity="0.5 1.5 2.0"/>
</multibody>"#;

const CANTILEVER: &str = r#"<multibody name="cantilever" version="1">
  <gravity value="0 -9.81 0"/>
  <ground><marker name="wall" position="0 0 0"/></ground>
  <flexible_body name="beam" modal="beam.json" position="0 0 0">
    <marker name="root" node="0"/>
  </flexible_body>
  <joint name="clamp" type="fixed" i="beam.root" j="ground.wall"/>
</multibody>"#;

/// The suspension example with its lower arm's data in `arm.json` (`elements` elements:
/// spring seat at 3/4 of the arm, ball joint at its end) and a 1 cm road step.
fn suspension(elements: usize) -> String {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/models/flexible/suspension.xml")).unwrap();
    text.replace("suspension_lower_arm.json", "arm.json")
        .replace(r#"node="6""#, &format!(r#"node="{}""#, 3 * elements / 4))
        .replace(r#"node="8""#, &format!(r#"node="{elements}""#))
        .replace(r#"<input name="zr" start="0""#, r#"<input name="zr" start="0.01""#)
}

/// The suspension's lower arm (as in the example) with `elements` elements and `modes`
/// Craig–Bampton modes (6 constraint modes for its two joint nodes plus fixed ones).
fn arm(elements: usize, modes: usize) -> mbfmu::modal::ModalData {
    beam(&BeamSpec {
        length: 0.4,
        elements,
        section: Section { area: 8e-4, iy: 5e-9, iz: 1e-8, j: 6e-9 },
        material: Material { young: 2.1e11, shear: 2.1e11 / 2.6, density: 7850.0 },
        modes,
        damping: Some(0.02),
        clamp: None,
        reduction: Reduction::CraigBampton { interface: vec![0, elements as u32], fixed_modes: modes - 6 },
        shear_coefficient: None,
    })
    .unwrap()
}

/// (simulation of 0.5 s, one linearization) in seconds.
fn run(dir: &std::path::Path, text: &str) -> (f64, f64) {
    std::fs::write(dir.join("m.xml"), text).unwrap();
    let m = mbfmu::model::load_file(&dir.join("m.xml")).unwrap_or_else(|e| panic!("{e}"));
    let t = Instant::now();
    let mut sim = Simulator::new(&m, SimOptions { tol: 1e-6, max_step: None, ..Default::default() }, 0.0).unwrap();
    sim.advance(0.5).unwrap();
    let t_sim = t.elapsed().as_secs_f64();
    let sel = select_states(sim.system(), sim.q(), sim.time(), &sim.inputs()).unwrap();
    let t = Instant::now();
    linearize(&mut sim, &sel, 1).unwrap();
    (t_sim, t.elapsed().as_secs_f64())
}

fn main() {
    let dir = std::env::temp_dir().join(format!("mbfmu-flex-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    println!(
        "{:<10} {:>6} {:>9} {:>10} {:>10} {:>10}",
        "model", "modes", "elements", "generate s", "simulate s", "linearize s"
    );
    for name in ["tumbling", "cantilever", "suspension"] {
        let mode_counts = if name == "suspension" { [6, 20, 50] } else { [5, 20, 50] };
        for modes in mode_counts {
            let mut times = Vec::new();
            for elements in [20, 200] {
                let t = Instant::now();
                let data = if name == "suspension" {
                    arm(elements, modes)
                } else {
                    beam(&BeamSpec {
                        length: 1.0,
                        elements,
                        section: Section { area: 1e-3, iy: 2e-9, iz: 1e-9, j: 3e-9 },
                        material: Material { young: 7e9, shear: 2.7e9, density: 2700.0 },
                        modes,
                        damping: Some(0.01),
                        clamp: (name == "cantilever").then_some(0),
                        reduction: Reduction::FreeInterface,
                        shear_coefficient: None,
                    })
                    .unwrap()
                };
                let t_gen = t.elapsed().as_secs_f64();
                let file = if name == "suspension" { "arm.json" } else { "beam.json" };
                std::fs::write(dir.join(file), write(&data)).unwrap();
                let text = match name {
                    "tumbling" => TUMBLING.to_string(),
                    "cantilever" => CANTILEVER.to_string(),
                    _ => suspension(elements),
                };
                let (ts, tl) = run(&dir, &text);
                println!("{name:<10} {modes:>6} {elements:>9} {t_gen:>10.3} {ts:>10.3} {tl:>10.4}");
                times.push((ts, tl));
            }
            println!(
                "{name:<10} {modes:>6}   ratio 200/20 elements: simulate {:.2}, linearize {:.2}",
                times[1].0 / times[0].0,
                times[1].1 / times[0].1
            );
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}
