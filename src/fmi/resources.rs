//! What an instance reads from its FMU's resources directory at instantiation (both FMI
//! versions): the model file, the start values it was packed with, and the linearization
//! states the packer selected ([`crate::pack`] writes them). No engine run.

use std::path::Path;

use super::guid::{guid, guid_with};
use super::interface::Interface;
use crate::dae::StartValues;
use crate::linearize::StateLayout;
use crate::model::Model;
use crate::model::overrides::{parse_start_values, start_values_text};

/// The state layout's file in the FMU's resources directory.
pub const LAYOUT_FILE: &str = "states.txt";

/// The start values' file in the FMU's resources directory (only when packed with some).
pub const START_VALUES_FILE: &str = "start_values.txt";

/// The model file in the FMU's resources directory.
pub const MODEL_FILE: &str = "model.xml";

/// The file naming the interfaces the FMU was packed with, one a line
/// (`ModelExchange`, `CoSimulation`); an FMU without it is Co-Simulation only.
pub const INTERFACES_FILE: &str = "interfaces.txt";

/// The interfaces an FMU offers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Interfaces {
    /// Model Exchange.
    pub model_exchange: bool,
    /// Co-Simulation.
    pub co_simulation: bool,
}

impl Interfaces {
    /// The file's text.
    pub fn to_text(self) -> String {
        let mut t = String::new();
        if self.model_exchange {
            t += "ModelExchange\n";
        }
        if self.co_simulation {
            t += "CoSimulation\n";
        }
        t
    }
}

/// The interfaces of the FMU whose resources directory is `resources`.
pub fn read_interfaces(resources: &Path) -> Result<Interfaces, String> {
    let file = resources.join(INTERFACES_FILE);
    let text = match std::fs::read_to_string(&file) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Ok(Interfaces { model_exchange: false, co_simulation: true });
        }
        Err(e) => return Err(format!("cannot read {}: {e}", file.display())),
    };
    let mut out = Interfaces { model_exchange: false, co_simulation: false };
    for (n, line) in text.lines().enumerate() {
        match line.trim() {
            "ModelExchange" => out.model_exchange = true,
            "CoSimulation" => out.co_simulation = true,
            "" => {}
            other => return Err(format!("{}:{}: unknown interface '{other}'", file.display(), n + 1)),
        }
    }
    Ok(out)
}

/// The state layout of the FMU whose resources directory is `resources` and whose model
/// has the GUID `guid` (read at instantiation; no engine run).
pub fn read_layout(resources: &Path, guid: &str) -> Result<StateLayout, String> {
    let file = resources.join(LAYOUT_FILE);
    let text = std::fs::read_to_string(&file).map_err(|e| format!("cannot read {}: {e}", file.display()))?;
    StateLayout::from_text(&text, guid).map_err(|e| format!("{}: {e}", file.display()))
}

/// The model of the FMU whose resources directory is `resources`, read from `model_text`
/// (`base`), with its start values applied, and its GUID (read at instantiation). No
/// `start_values.txt`: `base` and its plain GUID. A malformed file, an unknown name or a
/// value the model rejects is an error naming the file.
pub fn read_start_values(resources: &Path, base: Model, model_text: &str) -> Result<(Model, String), String> {
    let file = resources.join(START_VALUES_FILE);
    let text = match std::fs::read_to_string(&file) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            let own = guid(&base, model_text);
            return Ok((base, own));
        }
        Err(e) => return Err(format!("cannot read {}: {e}", file.display())),
    };
    let bad = |e: String| format!("{}: {e}", file.display());
    let pairs = parse_start_values(&text).map_err(bad)?;
    let overrides = base.resolve_overrides(&pairs).map_err(bad)?;
    let own = guid_with(&base, model_text, &start_values_text(&overrides));
    let model = base.with_overrides(&overrides).map_err(bad)?;
    StartValues::check_names(&model).map_err(bad)?;
    Ok((model, own))
}

/// The model (start values applied), its GUID and its linearization states, from the
/// resources directory `dir` of an FMU whose host passed `given` as its argument `what`
/// (FMI 2 `fmuGUID`, FMI 3 `instantiationToken`).
pub fn load(dir: &Path, what: &str, given: &str) -> Result<(Model, String, StateLayout), String> {
    let file = dir.join(MODEL_FILE);
    let model_text = std::fs::read_to_string(&file).map_err(|e| format!("cannot read {}: {e}", file.display()))?;
    let model = crate::model::parse::load_str(&model_text, &file.display().to_string())
        .map_err(|e| format!("invalid model: {e}"))?;
    let (model, own) = read_start_values(dir, model, &model_text).map_err(|e| format!("bad start values: {e}"))?;
    if given != own {
        return Err(format!("{what} {given} does not match this FMU's {own} (model {})", file.display()));
    }
    let layout = read_layout(dir, &own).map_err(|e| format!("no state layout: {e}"))?;
    Ok((model, own, layout))
}

/// As [`load`], for an instance of `interface`: an error when the FMU was packed without
/// that interface, or when Model Exchange is asked of a model without linearization
/// states (they are its continuous states).
pub fn load_for(
    dir: &Path,
    interface: Interface,
    what: &str,
    given: &str,
) -> Result<(Model, String, StateLayout), String> {
    let offers = read_interfaces(dir)?;
    let loaded = load(dir, what, given)?;
    match interface {
        Interface::ModelExchange if !offers.model_exchange => {
            Err("this FMU was packed without Model Exchange (mbfmu pack --kind me or both)".into())
        }
        Interface::ModelExchange if loaded.2.missing.is_some() => Err(format!(
            "Model Exchange needs the linearization states, and this model has none: {}",
            loaded.2.missing.as_deref().unwrap_or("")
        )),
        Interface::CoSimulation if !offers.co_simulation => {
            Err("this FMU was packed without Co-Simulation (mbfmu pack --kind cs or both)".into())
        }
        _ => Ok(loaded),
    }
}
