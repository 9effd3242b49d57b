//! Reading a scene: TOML text or a file parsed, resolved (an overhand knot fitted,
//! `[[rods]]` resolved one by one) and validated; parse errors as one line naming
//! every problem found, its field and position ([`crate::scene::problems`]).

use crate::scene::problems::{self, line_column, Problem};
use crate::scene::Scene;
use crate::Error;
use splinerod_core::Cancel;
use toml::de::DeTable;

impl Scene {
    /// Parses and validates a scene from TOML text.
    pub fn from_toml(text: &str) -> Result<Self, Error> {
        Self::from_toml_cancellable(text, &Cancel::none())
    }

    /// [`Scene::from_toml`], polling `cancel` during the setup that may take seconds
    /// (an overhand knot's fit): a stop asked returns [`Error::Interrupted`].
    pub fn from_toml_cancellable(text: &str, cancel: &Cancel) -> Result<Self, Error> {
        let mut scene: Scene = problems::read(text, missing_alternatives)?;
        if scene.resolve_rods(cancel)? {
            return Ok(scene);
        }
        scene.resolve_shape_with(cancel)?;
        scene.validate()?;
        Ok(scene)
    }

    /// Reads, parses and validates a scene file.
    pub fn load(path: impl AsRef<std::path::Path>) -> Result<Self, Error> {
        Self::load_cancellable(path, &Cancel::none())
    }

    /// [`Scene::load`], polling `cancel` as [`Scene::from_toml_cancellable`] does.
    pub fn load_cancellable(
        path: impl AsRef<std::path::Path>,
        cancel: &Cancel,
    ) -> Result<Self, Error> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|source| Error::Io {
            path: path.display().to_string(),
            source,
        })?;
        Self::from_toml_cancellable(&text, cancel).map_err(|e| match e {
            Error::Parse {
                position,
                message,
                field,
                ..
            } => Error::Parse {
                file: Some(path.display().to_string()),
                position,
                message,
                field,
            },
            Error::Format { problems, .. } => Error::Format {
                file: Some(path.display().to_string()),
                problems,
            },
            other => other,
        })
    }
}

/// One line from a TOML error: `line L, column C: message`, with a missing or unknown field
/// named by its dotted path (`rod.rest_length`) and any other error followed by its path.
pub(crate) fn parse_error(text: &str, e: &toml::de::Error) -> Error {
    // Without the input, the error's Display ends with "in `a.b`" naming the enclosing keys.
    let mut bare = e.clone();
    bare.set_input(None);
    let bare = bare.to_string();
    let path = bare
        .lines()
        .last()
        .and_then(|l| l.strip_prefix("in `")?.strip_suffix('`'))
        .unwrap_or("");
    let mut message = e.message().trim_end().to_string();
    let named = ["missing field `", "unknown field `"]
        .iter()
        .find(|p| message.starts_with(**p));
    match named {
        Some(p) if !path.is_empty() => message.insert_str(p.len(), &format!("{path}.")),
        _ if !path.is_empty() => message.push_str(&format!(" in `{path}`")),
        _ => {}
    }
    let field = match named {
        Some(p) => message[p.len()..].split('`').next().map(str::to_string),
        None => Some(path.to_string()).filter(|p| !p.is_empty()),
    };
    Error::Parse {
        file: None,
        position: e.span().map(|span| line_column(text, span.start)),
        message,
        field,
    }
}

/// The required fields of a scene `table` serde cannot name, being one of two: no
/// `[rod]` and no `[[rods]]`, or a rod with neither `rest_length` nor `overhand`.
fn missing_alternatives(table: &DeTable<'_>) -> Vec<Problem> {
    let mut missing = Vec::new();
    let mut rods: Vec<(String, &DeTable<'_>)> = Vec::new();
    match (table.get("rod"), table.get("rods")) {
        (None, None) => missing.push(Problem::Missing {
            field: "rod".into(),
            table: true,
            note: Some("or [[rods]]".into()),
        }),
        (Some(rod), _) => rods.extend(rod.get_ref().as_table().map(|t| ("rod".into(), t))),
        (None, Some(list)) => {
            let list = list.get_ref().as_array().map(|a| a.iter()).into_iter();
            for (i, rod) in list.flatten().enumerate() {
                rods.extend(rod.get_ref().as_table().map(|t| (format!("rods[{i}]"), t)));
            }
        }
    }
    for (path, rod) in rods {
        if rod.get("rest_length").is_none() && rod.get("overhand").is_none() {
            missing.push(Problem::Missing {
                field: format!("{path}.rest_length"),
                table: false,
                note: Some(format!("required unless {path}.overhand gives the shape")),
            });
        }
    }
    missing
}
