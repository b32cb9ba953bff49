//! Reading a modal data file (JSON, MODEL_FORMAT.md "Modal data files") into a validated
//! [`ModalData`]. serde_json parses the text (syntax errors carry line:column); the
//! document is then walked by hand so that every error names its entry exactly
//! (`modes[2].shape[7]`, `nodes[3].mass`).
//!
//! Validated: the format tag and version; no unknown fields; every number finite; node ids
//! unique, masses > 0, inertias ≥ 0; one 6-vector per node in every shape; frequencies and
//! damping ratios ≥ 0, given for every mode or none; not both frequencies and a stiffness
//! matrix; damping ratios only with frequencies; with frequencies, modes mass-normalized
//! (ΦᵀMΦ = I, [`super::matrix_checks`]); matrices n_m × n_m, symmetric, positive
//! semidefinite.

use std::collections::BTreeMap;
use std::path::Path;

use serde_json::{Map, Value};

use super::data::{ModalDamping, ModalData, ModalStiffness, Node};
use super::error::ModalError;
use super::matrix_checks::{NORMALIZATION_TOL, asymmetry, indefinite, not_normalized};

/// The value of the top-level "format" field.
pub const FORMAT: &str = "mbfmu-modal";
/// The format version this reader reads and the writer writes.
pub const VERSION: u64 = 1;

/// Read and validate the modal data file at `path`.
pub fn read(path: &Path) -> Result<ModalData, ModalError> {
    let name = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| ModalError::Io { path: name.clone(), what: e.to_string() })?;
    parse(&text, &name)
}

/// Parse and validate the text of a modal data file; `origin` names it in messages.
pub fn parse(text: &str, origin: &str) -> Result<ModalData, ModalError> {
    let doc: Value = serde_json::from_str(text).map_err(|e| {
        let msg = e.to_string();
        let what = match msg.rfind(" at line ") {
            Some(i) => msg[..i].to_string(),
            None => msg,
        };
        ModalError::Syntax { path: origin.to_string(), line: e.line(), column: e.column(), what }
    })?;
    Reader { origin }.document(&doc)
}

/// The walk over the document; `origin` is the file name of every message.
struct Reader<'a> {
    origin: &'a str,
}

/// The frequency and damping ratio a mode may carry.
struct ModeExtras {
    frequency: Option<f64>,
    damping_ratio: Option<f64>,
}

/// Mode shapes, `[mode][node]`.
type Shapes = Vec<Vec<[f64; 6]>>;

/// How a value is described in messages: `null`, `the string "NaN"`, `an array`, `1.5`.
fn describe(v: &Value) -> String {
    match v {
        Value::Null => "null".into(),
        Value::Bool(b) => b.to_string(),
        Value::Number(n) => n.to_string(),
        Value::String(s) => format!("the string {}", Value::String(s.clone())),
        Value::Array(_) => "an array".into(),
        Value::Object(_) => "an object".into(),
    }
}

impl Reader<'_> {
    fn err<T>(&self, entry: impl Into<String>, what: impl Into<String>) -> Result<T, ModalError> {
        Err(ModalError::Entry { path: self.origin.to_string(), entry: entry.into(), what: what.into() })
    }

    /// The object at `entry`, with no fields but `allowed`.
    fn object<'v>(&self, v: &'v Value, entry: &str, allowed: &[&str]) -> Result<&'v Map<String, Value>, ModalError> {
        let Value::Object(map) = v else {
            return self.err(entry, format!("expected an object, found {}", describe(v)));
        };
        if let Some(k) = map.keys().find(|k| !allowed.contains(&k.as_str())) {
            let list: Vec<String> = allowed.iter().map(|a| format!("\"{a}\"")).collect();
            return self.err(join(entry, k), format!("unknown field (expected one of {})", list.join(", ")));
        }
        Ok(map)
    }

    fn required<'v>(&self, map: &'v Map<String, Value>, entry: &str, key: &str) -> Result<&'v Value, ModalError> {
        map.get(key).map_or_else(|| self.err(join(entry, key), "missing"), Ok)
    }

    fn array<'v>(&self, v: &'v Value, entry: &str) -> Result<&'v [Value], ModalError> {
        match v {
            Value::Array(a) => Ok(a),
            _ => self.err(entry, format!("expected an array, found {}", describe(v))),
        }
    }

    fn number(&self, v: &Value, entry: &str) -> Result<f64, ModalError> {
        match v.as_f64() {
            Some(x) if x.is_finite() => Ok(x),
            _ => self.err(entry, format!("expected a finite number, found {}", describe(v))),
        }
    }

    /// A number ≥ 0 (`strict`: > 0).
    fn nonnegative(&self, v: &Value, entry: &str, strict: bool) -> Result<f64, ModalError> {
        let x = self.number(v, entry)?;
        if strict && x <= 0.0 {
            return self.err(entry, format!("must be > 0, found {x}"));
        }
        if x < 0.0 {
            return self.err(entry, format!("must be ≥ 0, found {x}"));
        }
        Ok(x)
    }

    /// An array of exactly N finite numbers.
    fn vector<const N: usize>(&self, v: &Value, entry: &str) -> Result<[f64; N], ModalError> {
        let a = self.array(v, entry)?;
        if a.len() != N {
            return self.err(entry, format!("expected {N} numbers, found {}", a.len()));
        }
        let mut out = [0.0; N];
        for (i, x) in a.iter().enumerate() {
            out[i] = self.number(x, &format!("{entry}[{i}]"))?;
        }
        Ok(out)
    }

    fn document(&self, doc: &Value) -> Result<ModalData, ModalError> {
        let allowed = ["format", "version", "description", "nodes", "modes", "stiffness", "damping"];
        let map = self.object(doc, "document", &allowed)?;
        let format = self.required(map, "", "format")?;
        if format.as_str() != Some(FORMAT) {
            return self.err("format", format!("expected the string \"{FORMAT}\", found {}", describe(format)));
        }
        let version = self.required(map, "", "version")?;
        if version.as_u64() != Some(VERSION) {
            return self.err("version", format!("expected {VERSION}, found {}", describe(version)));
        }
        let description = match map.get("description") {
            None => None,
            Some(Value::String(s)) => Some(s.clone()),
            Some(v) => return self.err("description", format!("expected a string, found {}", describe(v))),
        };
        let nodes = self.nodes(self.required(map, "", "nodes")?)?;
        let (modes, extras) = self.modes(self.required(map, "", "modes")?, nodes.len())?;
        let n = modes.len();
        let stiffness_matrix = map.get("stiffness").map(|v| self.matrix(v, "stiffness", n)).transpose()?;
        let damping_matrix = map.get("damping").map(|v| self.matrix(v, "damping", n)).transpose()?;
        let stiffness = match stiffness_matrix {
            Some(k) => {
                if let Some(i) = extras.iter().position(|e| e.frequency.is_some()) {
                    let what = "a mode frequency and a \"stiffness\" matrix are both given; give one of them";
                    return self.err(format!("modes[{i}].frequency"), what);
                }
                ModalStiffness::Matrix(k)
            }
            None => {
                if let Some(i) = extras.iter().position(|e| e.frequency.is_none()) {
                    return self.err(
                        format!("modes[{i}].frequency"),
                        "missing (give every mode a frequency, or a \"stiffness\" matrix)",
                    );
                }
                ModalStiffness::Frequencies(extras.iter().filter_map(|e| e.frequency).collect())
            }
        };
        let damping = self.damping(&extras, &stiffness, damping_matrix)?;
        let data = ModalData { description, nodes, modes, stiffness, damping };
        if matches!(data.stiffness, ModalStiffness::Frequencies(_))
            && let Some((k, l, v)) = not_normalized(&data.modal_mass())
        {
            let what = format!(
                "modes given with frequencies must be mass-normalized with respect to the node masses and inertias \
                 (ΦᵀMΦ = I to {NORMALIZATION_TOL:e}), but (ΦᵀMΦ)[{k}][{l}] = {v}"
            );
            return self.err(format!("modes[{l}]"), what);
        }
        Ok(data)
    }

    fn nodes(&self, v: &Value) -> Result<Vec<Node>, ModalError> {
        let items = self.array(v, "nodes")?;
        if items.is_empty() {
            return self.err("nodes", "expected at least one node");
        }
        let mut seen: BTreeMap<u32, usize> = BTreeMap::new();
        let mut nodes = Vec::with_capacity(items.len());
        for (i, item) in items.iter().enumerate() {
            let entry = format!("nodes[{i}]");
            let map = self.object(item, &entry, &["id", "position", "mass", "inertia"])?;
            let id_value = self.required(map, &entry, "id")?;
            let id = match id_value.as_u64().and_then(|x| u32::try_from(x).ok()) {
                Some(id) => id,
                None => {
                    let what = format!("expected an integer from 0 to {}, found {}", u32::MAX, describe(id_value));
                    return self.err(format!("{entry}.id"), what);
                }
            };
            if let Some(first) = seen.insert(id, i) {
                return self.err(format!("{entry}.id"), format!("duplicate node id {id} (also nodes[{first}].id)"));
            }
            let position = self.vector::<3>(self.required(map, &entry, "position")?, &format!("{entry}.position"))?;
            let mass = self.nonnegative(self.required(map, &entry, "mass")?, &format!("{entry}.mass"), true)?;
            let inertia_entry = format!("{entry}.inertia");
            let inertia = self.vector::<3>(self.required(map, &entry, "inertia")?, &inertia_entry)?;
            if let Some(k) = inertia.iter().position(|&x| x < 0.0) {
                return self.err(format!("{inertia_entry}[{k}]"), format!("must be ≥ 0, found {}", inertia[k]));
            }
            nodes.push(Node { id, position, mass, inertia });
        }
        Ok(nodes)
    }

    fn modes(&self, v: &Value, n_nodes: usize) -> Result<(Shapes, Vec<ModeExtras>), ModalError> {
        let items = self.array(v, "modes")?;
        let mut shapes = Vec::with_capacity(items.len());
        let mut extras = Vec::with_capacity(items.len());
        for (k, item) in items.iter().enumerate() {
            let entry = format!("modes[{k}]");
            let map = self.object(item, &entry, &["frequency", "damping_ratio", "shape"])?;
            let opt =
                |key: &str| map.get(key).map(|v| self.nonnegative(v, &format!("{entry}.{key}"), false)).transpose();
            let frequency = opt("frequency")?;
            let damping_ratio = opt("damping_ratio")?;
            let shape_entry = format!("{entry}.shape");
            let rows = self.array(self.required(map, &entry, "shape")?, &shape_entry)?;
            if rows.len() != n_nodes {
                let what =
                    format!("expected {n_nodes} rows [dx, dy, dz, rx, ry, rz] (one per node), found {}", rows.len());
                return self.err(shape_entry, what);
            }
            let shape = rows
                .iter()
                .enumerate()
                .map(|(i, r)| self.vector::<6>(r, &format!("{shape_entry}[{i}]")))
                .collect::<Result<_, _>>()?;
            shapes.push(shape);
            extras.push(ModeExtras { frequency, damping_ratio });
        }
        Ok((shapes, extras))
    }

    /// An n × n matrix of finite numbers, symmetric and positive semidefinite.
    fn matrix(&self, v: &Value, entry: &str, n: usize) -> Result<Vec<Vec<f64>>, ModalError> {
        let rows = self.array(v, entry)?;
        if rows.len() != n {
            return self.err(entry, format!("expected {n} rows (one per mode), found {}", rows.len()));
        }
        let mut a = Vec::with_capacity(n);
        for (i, r) in rows.iter().enumerate() {
            let row_entry = format!("{entry}[{i}]");
            let row = self.array(r, &row_entry)?;
            if row.len() != n {
                return self.err(row_entry, format!("expected {n} numbers (one per mode), found {}", row.len()));
            }
            a.push(
                row.iter()
                    .enumerate()
                    .map(|(j, x)| self.number(x, &format!("{row_entry}[{j}]")))
                    .collect::<Result<_, _>>()?,
            );
        }
        if let Some((i, j)) = asymmetry(&a) {
            return self.err(
                format!("{entry}[{i}][{j}]"),
                format!("not symmetric: {} but {entry}[{j}][{i}] = {}", a[i][j], a[j][i]),
            );
        }
        if let Some((min, max)) = indefinite(&a) {
            return self
                .err(entry, format!("not positive semidefinite: eigenvalue {min:e} (largest magnitude {max:e})"));
        }
        Ok(a)
    }

    fn damping(
        &self,
        extras: &[ModeExtras],
        stiffness: &ModalStiffness,
        matrix: Option<Vec<Vec<f64>>>,
    ) -> Result<ModalDamping, ModalError> {
        let with = extras.iter().position(|e| e.damping_ratio.is_some());
        let without = extras.iter().position(|e| e.damping_ratio.is_none());
        match (matrix, with) {
            (Some(c), None) => Ok(ModalDamping::Matrix(c)),
            (Some(_), Some(i)) => self.err(
                format!("modes[{i}].damping_ratio"),
                "a mode damping ratio and a \"damping\" matrix are both given; give one of them",
            ),
            (None, None) => Ok(ModalDamping::None),
            (None, Some(i)) => {
                if let ModalStiffness::Matrix(_) = stiffness {
                    let what =
                        "a damping ratio needs mode frequencies; with a \"stiffness\" matrix give a \"damping\" matrix";
                    return self.err(format!("modes[{i}].damping_ratio"), what);
                }
                if let Some(j) = without {
                    return self.err(
                        format!("modes[{j}].damping_ratio"),
                        format!("missing (modes[{i}] has one: give every mode a damping ratio, or none)"),
                    );
                }
                Ok(ModalDamping::Ratios(extras.iter().filter_map(|e| e.damping_ratio).collect()))
            }
        }
    }
}

/// `entry.key`, or `key` at the top level.
fn join(entry: &str, key: &str) -> String {
    if entry.is_empty() || entry == "document" { key.to_string() } else { format!("{entry}.{key}") }
}
