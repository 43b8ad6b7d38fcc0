//! Writing a scene description as a scene file, with comments.
//!
//! [`SceneFile::to_toml`] writes the tables in the order a reader expects
//! them (camera, film, integrator, materials, shapes, lights), the keys of
//! each in the order of the schema's fields and none at its default, a
//! shape's `transform` as an inline table, and the comments above the
//! tables they describe. The text is read back before it is returned and
//! must give the same description (tested over random descriptions in
//! `crates/render/tests/scene_write.rs`).

use super::desc::SceneDesc;
use std::collections::BTreeMap;
use toml_edit::{DocumentMut, Item, Table};

/// Why a scene could not be written.
#[derive(Debug, thiserror::Error)]
pub enum WriteError {
    /// The serialiser refused a value.
    #[error("cannot write the scene as TOML: {0}")]
    Toml(#[from] toml_edit::ser::Error),
    /// The text would read back as another scene, or not at all.
    #[error(
        "the scene cannot be written as TOML ({0}); TOML integers end at 2^63 − 1 (a `seed` or \
         `spp` beyond it cannot be written)"
    )]
    NotKept(String),
}

/// Comments written above a scene file's tables: plain text, one comment
/// line per line of text (`# ` is added).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Comments {
    /// At the top of the file.
    pub header: String,
    /// Above `[materials.NAME]`, by name.
    pub materials: BTreeMap<String, String>,
    /// Above the `[[shapes]]` entry of the same index.
    pub shapes: Vec<String>,
    /// Above the `[[lights]]` entry of the same index.
    pub lights: Vec<String>,
}

/// A scene as data: its description and the comments written with it.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneFile {
    /// What the scene is.
    pub desc: SceneDesc,
    /// What the file says about it.
    pub comments: Comments,
}

impl SceneFile {
    /// A description without comments.
    pub fn new(desc: SceneDesc) -> SceneFile {
        SceneFile {
            desc,
            comments: Comments::default(),
        }
    }

    /// The scene file's text. Fails for a value TOML cannot hold (an
    /// integer beyond i64, such as a seed ≥ 2⁶³).
    pub fn to_toml(&self) -> Result<String, WriteError> {
        let c = &self.comments;
        // Every table comes out inline; the file's tables are made from them.
        let mut doc: DocumentMut = toml_edit::ser::to_document(&self.desc)?;
        let root = doc.as_table_mut();
        let mut position = 0;
        let mut place = |t: &mut Table, note: &str| {
            t.set_position(Some(position));
            position += 1;
            t.decor_mut().set_prefix(format!("\n{}", comment(note)));
        };
        for name in ["camera", "film", "integrator"] {
            if let Some(t) = root.get_mut(name).and_then(table) {
                place(t, "");
            }
        }
        if let Some(materials) = root.get_mut("materials").and_then(table) {
            materials.set_implicit(true);
            for (name, m) in materials.iter_mut() {
                if let Some(t) = table(m) {
                    place(t, c.materials.get(name.get()).map_or("", String::as_str));
                }
            }
        }
        for (list, notes) in [("shapes", &c.shapes), ("lights", &c.lights)] {
            let Some(item) = root.get_mut(list) else {
                continue;
            };
            make_tables(item);
            if let Some(entries) = item.as_array_of_tables_mut() {
                for (i, t) in entries.iter_mut().enumerate() {
                    place(t, notes.get(i).map_or("", String::as_str));
                }
            }
        }
        let text = format!("{}{}", comment(&c.header), doc);
        // One newline at the end, none before the first table.
        let text = format!("{}\n", text.trim_start_matches('\n').trim_end());
        self.check_reads_back(&text)?;
        Ok(text)
    }

    /// Whether `text` reads back as this description; compared as
    /// serialised, so that a NaN reads back as itself.
    fn check_reads_back(&self, text: &str) -> Result<(), WriteError> {
        let serialised = |d: &SceneDesc| toml_edit::ser::to_string(d);
        match toml::from_str::<SceneDesc>(text) {
            Ok(back) if serialised(&back)? == serialised(&self.desc)? => Ok(()),
            Ok(_) => Err(WriteError::NotKept("it reads back as another scene".into())),
            Err(e) => Err(WriteError::NotKept(e.message().trim().to_string())),
        }
    }
}

/// An inline table made a table, an array of inline tables an array of
/// tables (their own inline tables stay inline); anything else unchanged.
fn make_tables(item: &mut Item) {
    *item = match std::mem::take(item).into_table() {
        Ok(t) => Item::Table(t),
        Err(other) => match other.into_array_of_tables() {
            Ok(a) => Item::ArrayOfTables(a),
            Err(other) => other,
        },
    };
}

/// `item` made a table (from the inline table it was serialised as).
fn table(item: &mut Item) -> Option<&mut Table> {
    make_tables(item);
    item.as_table_mut()
}

/// `text` as comment lines, each ending in a newline. Control characters
/// other than tab, which TOML does not allow in a comment, become spaces.
fn comment(text: &str) -> String {
    text.lines()
        .map(|line| {
            let line: String = line
                .chars()
                .map(|c| if c.is_control() && c != '\t' { ' ' } else { c })
                .collect();
            format!("{}\n", format!("# {line}").trim_end())
        })
        .collect()
}
