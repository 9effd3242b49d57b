//! `splinerod fit --scene-out FITTED.toml`: the scene file the fit started from with the
//! fitted values written in place of the starting ones — comments, order and layout
//! kept (`toml_edit`), so the result reads as the user's own scene, ready to run.
//!
//! A parameter path (as [`crate::sensitivity::set_parameter`] reads it: `rod.<field>`,
//! `rods[k].<field>`, `world.gravity[c]`, `loads[i].force[c]`, `contact.friction`) is
//! followed key by key and index by index (a fitted `pins[i].position[c]` is refused:
//! a file's pin must agree with the rod's start); a gravity the file leaves at its default is written out whole.
//! The result is parsed again as a scene, and every fitted value read back from it
//! must equal the fit's bit for bit (a text round trip — shortest round-trip decimals,
//! no arithmetic — so under any kernel set).

use crate::sensitivity::{parameter_value, set_parameter};
use crate::{Error, Real, Scene};
use toml_edit::{DocumentMut, Item, Value};

/// `text` (the scene file `file`) with each parameter `names[k]` set to `values[k]`.
pub fn with_fitted_values(
    file: &str,
    text: &str,
    names: &[String],
    values: &[Real],
) -> Result<String, Error> {
    let bad = |reason: String| Error::field("--scene-out", file, reason);
    let mut doc: DocumentMut = text.parse().map_err(|e| bad(format!("{e}")))?;
    let mut expected = Scene::from_toml(text)?;
    for (name, &v) in names.iter().zip(values) {
        if name.starts_with("pins[") {
            let reason = format!(
                "{name}: a scene file's pin must agree with where the rod starts, so a \
                 fitted pin position is reported, not written"
            );
            return Err(bad(reason));
        }
        set_parameter(&mut expected, name, v)?;
        if name.starts_with("world.gravity[") {
            // The whole vector: the file may leave gravity at its default.
            let gravity: toml_edit::Array = expected.world.gravity.iter().copied().collect();
            doc["world"]["gravity"] = toml_edit::value(gravity);
            continue;
        }
        let item = walk(doc.as_item_mut(), name)
            .ok_or_else(|| bad(format!("{name} is not a value written in the file")))?;
        replace(item, v);
    }
    let out = doc.to_string();
    let written = Scene::from_toml(&out)?;
    for name in names {
        let (a, b) = (
            parameter_value(&written, name)?,
            parameter_value(&expected, name)?,
        );
        if a.to_bits() != b.to_bits() {
            return Err(bad(format!("{name} reads back as {a}, not {b}")));
        }
    }
    Ok(out)
}

/// The item at the parameter path `path` (`a.b[1].c`), if the file has it.
fn walk<'a>(mut item: &'a mut Item, path: &str) -> Option<&'a mut Item> {
    for segment in path.split('.') {
        let (key, indices) = match segment.find('[') {
            Some(i) => (&segment[..i], &segment[i..]),
            None => (segment, ""),
        };
        item = item.get_mut(key)?;
        for index in indices.split_terminator(']') {
            let k: usize = index.strip_prefix('[')?.parse().ok()?;
            item = item.get_mut(k)?;
        }
    }
    Some(item)
}

/// Sets the value `item` to `v`, keeping its comments and spacing.
fn replace(item: &mut Item, v: Real) {
    let mut new = Value::from(v);
    if let Some(old) = item.as_value() {
        *new.decor_mut() = old.decor().clone();
    }
    *item = Item::Value(new);
}
