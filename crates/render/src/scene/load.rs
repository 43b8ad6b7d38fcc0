//! Reading a scene file and parsing it into its description, with
//! positioned errors and the fix for the usual mistakes of TOML's table
//! syntax.

use super::Scene;
use super::build;
use super::desc::SceneDesc;
use crate::error::SceneError;
use crate::inputs;
use std::path::Path;

/// Parses a scene file's text into its description, with positioned errors.
pub fn parse(path: &Path, text: &str) -> Result<SceneDesc, SceneError> {
    toml::from_str::<SceneDesc>(text).map_err(|e| {
        let mut msg = e.message().trim().to_string();
        if let Some(hint) = e.span().and_then(|span| duplicate_hint(text, &msg, span)) {
            msg = hint;
        } else if let Some(hint) = shape_hint(text) {
            msg = format!("{msg} ({hint})");
        }
        match e.span() {
            Some(span) => SceneError::at(path, text, span.start, msg),
            None => SceneError::new(path, msg),
        }
    })
}

/// The tables a scene holds as arrays of tables, with what one entry is.
const ARRAYS_OF_TABLES: [(&str, &str); 2] = [("shapes", "shape"), ("lights", "light")];

/// The fix for an array of tables written as a table twice (`[lights]` …
/// `[lights]`), which toml reports only as "duplicate key", at the second
/// header: the key named, and the brackets to write.
fn duplicate_hint(text: &str, msg: &str, span: std::ops::Range<usize>) -> Option<String> {
    if !msg.starts_with("duplicate key") {
        return None;
    }
    let key = text.get(span.clone())?.trim().trim_matches(['"', '\'']);
    let (key, one) = ARRAYS_OF_TABLES.into_iter().find(|(k, _)| *k == key)?;
    // Only a table header: a duplicated key inside a table (`lights = 1`
    // twice) is another mistake, which the bare message describes.
    let line_start = text[..span.start].rfind('\n').map_or(0, |i| i + 1);
    if !text[line_start..span.start].trim_start().starts_with('[') {
        return None;
    }
    Some(format!(
        "duplicate key `{key}` ({key} are an array of tables: write [[{key}]] (two \
         brackets) for each {one})"
    ))
}

/// The fix for a top-level table written with the wrong brackets, which
/// serde reports only as a type mismatch ("invalid type: map, expected a
/// sequence").
fn shape_hint(text: &str) -> Option<String> {
    let table: toml::Table = text.parse().ok()?;
    for (key, one) in ARRAYS_OF_TABLES {
        if matches!(table.get(key), Some(v) if !v.is_array()) {
            return Some(format!(
                "{key} are an array of tables: write [[{key}]] before each {one}"
            ));
        }
    }
    match table.get("materials") {
        Some(toml::Value::Table(m)) if m.values().all(toml::Value::is_table) => None,
        Some(_) => Some(
            "materials are named tables: write [materials.NAME] (single brackets) before each \
             material's keys"
                .to_string(),
        ),
        None => None,
    }
}

/// Loads and builds a scene file.
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    let text = read_scene_text(path)?;
    load_str(path, &text)
}

/// Reads a scene file: at most [`inputs::MAX_SCENE_BYTES`], UTF-8.
fn read_scene_text(path: &Path) -> Result<String, SceneError> {
    let bytes = safe_io::read_input(path, "scene file", inputs::MAX_SCENE_BYTES).map_err(|e| {
        let hint = match e {
            safe_io::ReadError::TooLarge { .. } => {
                " (scenes describe geometry by reference: put meshes in OBJ files)"
            }
            _ => "",
        };
        SceneError::new(path, format!("{e}{hint}"))
    })?;
    String::from_utf8(bytes).map_err(|e| {
        let off = e.utf8_error().valid_up_to();
        let text = String::from_utf8_lossy(e.as_bytes()).into_owned();
        SceneError::at(path, &text, off, "the scene file is not UTF-8 text")
    })
}

/// Builds a scene from its text (`path` locates relative files and errors).
pub fn load_str(path: &Path, text: &str) -> Result<Scene, SceneError> {
    if text.len() as u64 > inputs::MAX_SCENE_BYTES {
        return Err(SceneError::new(
            path,
            format!(
                "the scene text is larger than {} MiB",
                inputs::MAX_SCENE_BYTES >> 20
            ),
        ));
    }
    let desc = parse(path, text)?;
    build::build(path, text, &desc)
}
