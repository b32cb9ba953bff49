//! Identity of an FMU: its GUID (a hash of the model text, the modal data of its flexible
//! bodies, the start values packed with it and the engine version, so a changed model,
//! modal data, start value or engine gives a new GUID) and its modelIdentifier (from the
//! model name).

use crate::model::Model;

/// Engine version: crate version and a fingerprint of the engine sources (build.rs).
pub const ENGINE_VERSION: &str = concat!(env!("CARGO_PKG_VERSION"), "+", env!("MBFMU_ENGINE_FINGERPRINT"));

/// 128-bit FNV-1a.
fn fnv1a128(parts: &[&[u8]]) -> u128 {
    let mut h: u128 = 0x6c62272e07bb014262b821756295c58d;
    let prime: u128 = 0x0000000001000000000000000000013B;
    for p in parts {
        for b in *p {
            h ^= *b as u128;
            h = h.wrapping_mul(prime);
        }
        h ^= 0xff;
        h = h.wrapping_mul(prime);
    }
    h
}

/// A 64-bit checksum of `bytes` (FNV-1a), against corrupted serialized states.
pub fn checksum(bytes: &[u8]) -> u64 {
    fnv1a128(&[bytes]) as u64
}

/// The GUID of the FMU of `model`, read from `model_text`: `{8-4-4-4-12}` hex digits.
/// The modal data of the flexible bodies enter by their values
/// ([`Model::modal_data_texts`]), not their files' formatting.
pub fn guid(model: &Model, model_text: &str) -> String {
    guid_with(model, model_text, "")
}

/// The GUID of the FMU of `model` packed with the start values `start_values` (the text of
/// its `resources/start_values.txt`, [`crate::model::overrides::start_values_text`]; empty:
/// none, and then the GUID is [`guid`]'s).
pub fn guid_with(model: &Model, model_text: &str, start_values: &str) -> String {
    let modal = model.modal_data_texts();
    let mut parts = vec![ENGINE_VERSION.as_bytes(), model_text.as_bytes()];
    parts.extend(modal.iter().map(|m| m.as_bytes()));
    if !start_values.is_empty() {
        parts.extend([b"start_values".as_slice(), start_values.as_bytes()]);
    }
    let h = fnv1a128(&parts);
    let s = format!("{h:032x}");
    format!("{{{}-{}-{}-{}-{}}}", &s[0..8], &s[8..12], &s[12..16], &s[16..20], &s[20..32])
}

/// A C identifier from a model name (the format's names already are; anything else
/// becomes `_`, and a leading digit gets a `_` prefix).
pub fn model_identifier(name: &str) -> String {
    let mut s: String = name.chars().map(|c| if c.is_ascii_alphanumeric() || c == '_' { c } else { '_' }).collect();
    if s.is_empty() || s.starts_with(|c: char| c.is_ascii_digit()) {
        s.insert(0, '_');
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn of(text: &str) -> String {
        guid(&crate::model::parse::load_str(text, "m.xml").expect("a model"), text)
    }

    #[test]
    fn guid_changes_with_the_model_text_and_is_well_formed() {
        let (a, b) = (of("<multibody name=\"a\" version=\"1\"/>"), of("<multibody name=\"b\" version=\"1\"/>"));
        assert_ne!(a, b);
        assert_eq!(a, of("<multibody name=\"a\" version=\"1\"/>"));
        assert_eq!(a.len(), 38);
        assert!(a.starts_with('{') && a.ends_with('}'));
        assert_eq!(model_identifier("double pendulum-2"), "double_pendulum_2");
        assert_eq!(model_identifier("2d"), "_2d");
        let m = crate::model::parse::load_str("<multibody name=\"a\" version=\"1\"/>", "m.xml").unwrap();
        let text = "<multibody name=\"a\" version=\"1\"/>";
        assert_eq!(guid_with(&m, text, ""), a);
        assert_ne!(guid_with(&m, text, "x=1\n"), a);
        assert_ne!(guid_with(&m, text, "x=1\n"), guid_with(&m, text, "x=2\n"));
    }
}
