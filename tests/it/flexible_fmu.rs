//! A flexible-body model as an FMU: `mbfmu pack` carries its modal data file into
//! `resources/`, and the FMU's directional derivatives equal the engine's linearization
//! (A, B, C, D of `mbfmu::linearize`) at the same time, entry by entry.

use crate::common::host::{self, free, messages};
use crate::common::mbfmu;
use mbfmu::dae::{SimOptions, Simulator};
use mbfmu::fmi::exports_common::*;
use mbfmu::fmi::exports_cs::*;
use mbfmu::fmi::types::{CO_SIMULATION, Status};
use mbfmu::modal::{BeamSpec, Material, ModalData, Reduction, Section, beam, write};
use std::ffi::CString;

/// A cantilever (4 modes, node 0 clamped) with a lateral force input at its tip and the
/// tip's deflection and its acceleration as outputs.
const MODEL: &str = r#"<multibody name="flexcant" version="1">
  <gravity value="0 0 -9.81"/>
  <input name="F" start="0.5" unit="N"/>
  <ground><marker name="wall" position="0 0 0"/></ground>
  <flexible_body name="beam" modal="data/beam.json" position="0 0 0">
    <marker name="root" node="0"/>
    <marker name="tip" node="6"/>
  </flexible_body>
  <joint name="clamp" type="fixed" i="beam.root" j="ground.wall"/>
  <gforce name="push" i="beam.tip" force="0 F 0"/>
  <output name="tip_y" function="dy(beam.tip)"/>
  <output name="tip_az" function="accz(beam.tip)"/>
</multibody>
"#;

/// The cantilever's beam: 0.6 m, 6 elements, node 0 clamped, `modes` modes with damping
/// ratio `damping`.
fn cantilever_beam(modes: usize, damping: Option<f64>) -> ModalData {
    beam(&BeamSpec {
        length: 0.6,
        elements: 6,
        section: Section { area: 1e-3, iy: 2e-9, iz: 1e-9, j: 3e-9 },
        material: Material { young: 7e9, shear: 2.7e9, density: 2700.0 },
        modes,
        damping,
        clamp: Some(0),
        reduction: Reduction::FreeInterface,
        shear_coefficient: None,
    })
    .unwrap()
}

#[test]
fn the_fmu_of_a_flexible_model_carries_its_data_and_linearizes_like_the_engine() {
    let data = cantilever_beam(4, Some(0.02));
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("flexible-fmu");
    std::fs::create_dir_all(dir.join("data")).unwrap();
    let json = write(&data);
    std::fs::write(dir.join("data/beam.json"), &json).unwrap();
    let model = dir.join("flexcant.xml");
    std::fs::write(&model, MODEL).unwrap();
    let (fmu, unzipped) = (dir.join("flexcant.fmu"), dir.join("unzipped"));
    let arg = |p: &std::path::Path| p.to_str().expect("UTF-8 path").to_string();
    let o = mbfmu(&["pack", &arg(&model), "-o", &arg(&fmu), "--out-dir", &arg(&unzipped)]);
    assert!(o.status.success(), "pack failed: {}", String::from_utf8_lossy(&o.stderr));
    let packed =
        std::fs::read_to_string(unzipped.join("resources/data/beam.json")).expect("the modal data is in the FMU");
    assert_eq!(packed, json);
    let xml = std::fs::read_to_string(unzipped.join("modelDescription.xml")).unwrap();
    let start = xml.find(" guid=\"").unwrap() + 7;
    let guid = &xml[start..start + xml[start..].find('"').unwrap()];

    // The engine, at t = 0.02 after the same steps.
    let m = mbfmu::model::load_file(&model).unwrap();
    let mut sim = Simulator::new(&m, SimOptions { tol: 1e-10, max_step: None, ..Default::default() }, 0.0).unwrap();
    let sel = mbfmu::linearize::select_states(sim.system(), sim.q(), 0.0, &sim.inputs()).unwrap();
    sim.advance(0.01).unwrap();
    sim.advance(0.02).unwrap();
    let lin = mbfmu::linearize::linearize(&mut sim, &sel, 2).unwrap();
    assert_eq!(lin.states.len(), 8, "{:?}", lin.states);

    // The FMU, stepped the same way.
    let vars = mbfmu::fmi::variables::variables(
        &m,
        &mbfmu::linearize::StateLayout::at_start(&m),
        mbfmu::fmi::variables::Standard::Fmi2,
    );
    let path = unzipped.join("resources").display().to_string().replace('%', "%25").replace(' ', "%20");
    let (name, g, uri) = (c"flex", CString::new(guid).unwrap(), CString::new(format!("file://{path}")).unwrap());
    // SAFETY: valid NUL-terminated strings; the host's callbacks.
    let c = unsafe { host::instantiate(name.as_ptr(), CO_SIMULATION, g.as_ptr(), uri.as_ptr(), 0, 1) };
    assert!(!c.is_null());
    // SAFETY: a live instance and arrays of the stated lengths throughout.
    unsafe {
        assert_eq!(fmi2SetupExperiment(c, 1, 1e-10, 0.0, 0, 0.0), Status::Ok);
        assert_eq!(fmi2EnterInitializationMode(c), Status::Ok);
        assert_eq!(fmi2ExitInitializationMode(c), Status::Ok, "{:?}", messages(c));
        assert_eq!(fmi2DoStep(c, 0.0, 0.01, 1), Status::Ok, "{:?}", messages(c));
        assert_eq!(fmi2DoStep(c, 0.01, 0.01, 1), Status::Ok, "{:?}", messages(c));
    }
    // Row of an unknown: der(state) → A/B row of the state, an output → C/D row.
    // FMI names the derivative of der(x) as der(x,2).
    let state_of = |inner: &str| match inner.strip_suffix(",2") {
        Some(x) => format!("der({x})"),
        None => inner.to_string(),
    };
    let row = |n: &str| -> (bool, usize) {
        let inner = n.strip_prefix("der(").and_then(|s| s.strip_suffix(')')).map(state_of);
        match inner.and_then(|s| lin.states.iter().position(|x| *x == s)) {
            Some(i) => (true, i),
            None => (false, lin.outputs.iter().position(|x| x == n).unwrap_or_else(|| panic!("unknown {n}"))),
        }
    };
    let unknowns: Vec<_> = vars
        .iter()
        .filter(|v| v.unknown.is_some() || v.causality == mbfmu::fmi::variables::Causality::Output)
        .collect();
    let knowns: Vec<_> =
        vars.iter().filter(|v| v.known.is_some() || v.causality == mbfmu::fmi::variables::Causality::Input).collect();
    let uvr: Vec<u32> = unknowns.iter().map(|v| v.value_reference).collect();
    let mut worst = 0.0f64;
    for k in &knowns {
        let mut col = vec![0.0; uvr.len()];
        // SAFETY: as above.
        let st = unsafe {
            fmi2GetDirectionalDerivative(c, uvr.as_ptr(), uvr.len(), &k.value_reference, 1, &1.0, col.as_mut_ptr())
        };
        assert_eq!(st, Status::Ok, "{:?}", messages(c));
        let (is_state, j) = match lin.states.iter().position(|x| *x == k.name) {
            Some(j) => (true, j),
            None => (false, lin.inputs.iter().position(|x| *x == k.name).unwrap()),
        };
        for (u, got) in unknowns.iter().zip(col) {
            let (deriv, i) = row(&u.name);
            let want = match (deriv, is_state) {
                (true, true) => lin.a[(i, j)],
                (true, false) => lin.b[(i, j)],
                (false, true) => lin.c[(i, j)],
                (false, false) => lin.d[(i, j)],
            };
            let err = (got - want).abs() / want.abs().max(1.0);
            worst = worst.max(err);
            // Same engine, same steps: equal to the integrator's reproducibility (1e-9).
            assert!(err < 1e-9, "∂{}/∂{}: FMU {got} vs engine {want}", u.name, k.name);
        }
    }
    eprintln!("flexible FMU: {} knowns × {} unknowns, max relative difference {worst:e}", knowns.len(), uvr.len());
    free(c);
}

/// A modal data file given by an absolute path cannot travel with the FMU: `mbfmu pack`
/// refuses it at the element (exit code 2, `file:line:col`) and writes nothing.
#[test]
fn pack_refuses_modal_data_outside_the_model_directory() {
    let data = cantilever_beam(2, None);
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("flexible-fmu-outside");
    std::fs::create_dir_all(&dir).unwrap();
    let data_path = dir.join("beam.json");
    std::fs::write(&data_path, write(&data)).unwrap();
    let model = dir.join("abs.xml");
    std::fs::write(&model, MODEL.replace("data/beam.json", data_path.to_str().unwrap())).unwrap();
    let fmu = dir.join("abs.fmu");
    let arg = |p: &std::path::Path| p.to_str().expect("UTF-8 path").to_string();
    let o = mbfmu(&["pack", &arg(&model), "-o", &arg(&fmu)]);
    assert_eq!(o.status.code(), Some(2), "{}", String::from_utf8_lossy(&o.stderr));
    let err = String::from_utf8_lossy(&o.stderr);
    let want = format!(
        "{}:5:3: flexible_body 'beam': modal data '{}': to be packed into the FMU it must be a relative path inside the model file's directory",
        model.display(),
        data_path.display()
    );
    assert!(err.contains(&want), "{err}\nexpected: {want}");
    assert!(!fmu.exists());
}

/// The GUID covers the modal data: the same model text with other modal values gets
/// another GUID (an FMU whose data changed is another FMU), while the same values written
/// differently (whitespace) keep it.
#[test]
fn the_guid_changes_with_the_modal_data_values() {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("flexible-fmu-guid");
    std::fs::create_dir_all(dir.join("data")).unwrap();
    let label = dir.join("m.xml").display().to_string();
    let guid_with = |json: &str| {
        std::fs::write(dir.join("data/beam.json"), json).unwrap();
        let m = mbfmu::model::load_str(MODEL, &label).unwrap_or_else(|e| panic!("{e}"));
        mbfmu::fmi::guid::guid(&m, MODEL)
    };
    let json = write(&cantilever_beam(2, Some(0.02)));
    let g = guid_with(&json);
    assert_eq!(g, guid_with(&json.replace('\n', "\n  ")));
    assert_ne!(g, guid_with(&write(&cantilever_beam(2, Some(0.03)))));
}
