//! Reading model files: `extends`, deep merge, `--set` overrides, key-path errors.

use std::path::{Path, PathBuf};

use super::{Model, ModelError};

/// The embedded Dutch base model (`models/dutch-base.toml`), RPM3.
pub(crate) const BUILTIN_DUTCH: &str = include_str!("../../models/dutch-base.toml");

/// Where a model comes from.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ModelSource {
    /// The embedded default model.
    Builtin,
    /// A TOML file.
    File(PathBuf),
}

impl ModelSource {
    /// Display name for messages and reports.
    pub fn display(&self) -> String {
        match self {
            ModelSource::Builtin => "builtin:dutch".into(),
            ModelSource::File(p) => p.display().to_string(),
        }
    }
}

const MAX_DEPTH: usize = 8;

/// One override of a model value: a dotted key path (`fastening.vertical_stiffness`) and its
/// TOML value. The command line's `--set key=value` is parsed into one
/// ([`Assignment::parse`]); a study's parameters and the Python module's dict build them
/// directly, so their values are never printed and parsed again.
#[derive(Clone, Debug, PartialEq)]
pub struct Assignment {
    /// Dotted key path, each part non-empty.
    pub key: String,
    /// The value.
    pub value: toml::Value,
}

impl Assignment {
    /// `dotted.key=value` as on the command line. The value is TOML (`1.3e9`, `"RPM1"`,
    /// `[4, 10, 2]`, `true`); a bare word that is not valid TOML is taken as a string, so
    /// `fastening.model=RPM1` works.
    pub fn parse(arg: &str) -> Result<Self, ModelError> {
        let err = |message: &str| ModelError::Override {
            arg: arg.to_string(),
            message: message.to_string(),
        };
        let (key, raw) = arg
            .split_once('=')
            .ok_or_else(|| err("expected dotted.key=value, e.g. fastening.model=\"RPM1\""))?;
        let (key, raw) = (key.trim(), raw.trim());
        if key.is_empty() || key.split('.').any(str::is_empty) {
            return Err(err("empty key"));
        }
        let value = match format!("v = {raw}").parse::<toml::Table>() {
            Ok(mut t) => t.remove("v").expect("parsed key"),
            Err(_) if !raw.is_empty() && !raw.contains(['"', '\'', '[', '{', '=']) => {
                toml::Value::String(raw.to_string())
            }
            Err(e) => return Err(err(&format!("value is not TOML: {}", e.message()))),
        };
        Ok(Self {
            key: key.to_string(),
            value,
        })
    }
}

/// `key=value` with the value as TOML text (`fastening.vertical_stiffness=1300000000.0`).
impl std::fmt::Display for Assignment {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}={}", self.key, self.value)
    }
}

/// Loads a model from its source, merging `extends` bases and then `overrides`
/// (`dotted.key=value` strings, each parsed by [`Assignment::parse`] and applied in turn), and
/// validates it.
pub fn load_model(source: &ModelSource, overrides: &[String]) -> Result<Model, ModelError> {
    load_with(source, Overrides::Text(overrides))
}

/// Loads a model from its source, merging `extends` bases and then the `assignments` in
/// order, and validates it; messages name an assignment as it prints (`key=value`).
pub fn load_model_assigned(
    source: &ModelSource,
    assignments: &[Assignment],
) -> Result<Model, ModelError> {
    let shown: Vec<(Assignment, String)> = assignments
        .iter()
        .map(|a| (a.clone(), a.to_string()))
        .collect();
    load_model_shown(source, &shown)
}

/// [`load_model_assigned`] with each assignment's text for messages (e.g. a study file's `set`
/// entry as written).
pub fn load_model_shown(
    source: &ModelSource,
    assignments: &[(Assignment, String)],
) -> Result<Model, ModelError> {
    load_with(source, Overrides::Shown(assignments))
}

/// Overrides as the caller has them: text to parse one by one (after the model is read, as
/// the command line's `--set`), or assignments with their text for messages.
#[derive(Clone, Copy)]
enum Overrides<'a> {
    Text(&'a [String]),
    Shown(&'a [(Assignment, String)]),
}

impl Overrides<'_> {
    fn is_empty(&self) -> bool {
        match self {
            Overrides::Text(t) => t.is_empty(),
            Overrides::Shown(a) => a.is_empty(),
        }
    }

    /// Applies each override in order; text is parsed just before it is applied, so the
    /// first bad override is the one reported.
    fn apply(&self, table: &mut toml::Table) -> Result<(), ModelError> {
        match self {
            Overrides::Text(t) => t.iter().try_for_each(|arg| apply_override(table, arg)),
            Overrides::Shown(a) => a
                .iter()
                .try_for_each(|(a, shown)| apply_as(table, a, shown)),
        }
    }
}

fn load_with(source: &ModelSource, overrides: Overrides<'_>) -> Result<Model, ModelError> {
    match source {
        ModelSource::Builtin => load_str_with(BUILTIN_DUTCH, "builtin:dutch", overrides),
        ModelSource::File(path) => {
            let (table, chain) = read_table(path, 0)?;
            finish(table, &chain, overrides)
        }
    }
}

/// Loads a model from TOML text (`name` is used in messages; `extends` in the text is resolved
/// relative to the current directory), then applies overrides and validates.
pub fn load_model_str(text: &str, name: &str, overrides: &[String]) -> Result<Model, ModelError> {
    load_str_with(text, name, Overrides::Text(overrides))
}

fn load_str_with(text: &str, name: &str, overrides: Overrides<'_>) -> Result<Model, ModelError> {
    let table = parse(text, name)?;
    let (table, chain) = resolve_extends(table, name, Path::new("."), 0)?;
    finish(table, &chain, overrides)
}

fn finish(
    mut table: toml::Table,
    chain: &str,
    overrides: Overrides<'_>,
) -> Result<Model, ModelError> {
    overrides.apply(&mut table)?;
    let chain = if overrides.is_empty() {
        chain.to_string()
    } else {
        format!("{chain} with --set overrides")
    };
    let chain = chain.as_str();
    let model: Model =
        serde_path_to_error::deserialize(toml::Value::Table(table)).map_err(|e| {
            let key = e.path().to_string();
            let message = e.into_inner().message().to_string();
            ModelError::Key {
                file: chain.to_string(),
                key,
                message,
            }
        })?;
    model.validate(chain)?;
    Ok(model)
}

fn parse(text: &str, name: &str) -> Result<toml::Table, ModelError> {
    text.parse::<toml::Table>().map_err(|e| ModelError::Syntax {
        file: name.to_string(),
        message: e.to_string().trim().replace('\n', " "),
    })
}

fn read_table(path: &Path, depth: usize) -> Result<(toml::Table, String), ModelError> {
    let text = std::fs::read_to_string(path).map_err(|source| ModelError::Io {
        file: path.to_path_buf(),
        source,
    })?;
    let name = path.display().to_string();
    let table = parse(&text, &name)?;
    let dir = path.parent().unwrap_or(Path::new("."));
    resolve_extends(table, &name, dir, depth)
}

/// Returns the merged table and the chain of file names ("a.toml (extends b.toml)").
fn resolve_extends(
    mut table: toml::Table,
    name: &str,
    dir: &Path,
    depth: usize,
) -> Result<(toml::Table, String), ModelError> {
    if depth > MAX_DEPTH {
        return Err(ModelError::ExtendsLoop { file: name.into() });
    }
    let Some(ext) = table.remove("extends") else {
        return Ok((table, name.to_string()));
    };
    let toml::Value::String(base) = ext else {
        return Err(ModelError::Key {
            file: name.into(),
            key: "extends".into(),
            message: "must be a string: a path relative to this file, or \"builtin:dutch\"".into(),
        });
    };
    let (mut merged, base_chain) = if base == "builtin:dutch" {
        let t = parse(BUILTIN_DUTCH, "builtin:dutch")?;
        resolve_extends(t, "builtin:dutch", Path::new("."), depth + 1)?
    } else {
        let parent = dir.join(&base);
        match read_table(&parent, depth + 1) {
            Ok(t) => t,
            Err(ModelError::Io { file, source }) if file == parent => {
                return Err(ModelError::Key {
                    file: name.into(),
                    key: "extends".into(),
                    message: format!(
                        "\"{base}\" is {}: {source}. The path is relative to this file's directory: copy the parent file beside this one, or give its full path{}",
                        parent.display(),
                        own_key_errors(&table)
                    ),
                });
            }
            Err(e) => return Err(e),
        }
    };
    merge(&mut merged, table);
    Ok((merged, format!("{name} (extends {base_chain})")))
}

/// The key errors of a file's own keys when its parent cannot be read (so that a copied file
/// with a wrong `extends` does not hide its typos): the keys merged over the embedded default
/// model, whose unknown-key and type errors are told; range errors are not (they may depend
/// on the missing parent's values). Empty when there are none.
fn own_key_errors(table: &toml::Table) -> String {
    let Ok(mut probe) = parse(BUILTIN_DUTCH, "builtin:dutch") else {
        return String::new();
    };
    probe.remove("extends");
    merge(&mut probe, table.clone());
    match finish(probe, "this file", Overrides::Text(&[])) {
        Err(ModelError::Key { key, message, .. }) => {
            format!(". Besides, in this file's own keys: key `{key}`: {message}")
        }
        _ => String::new(),
    }
}

/// Deep merge: tables merge key by key, any other value replaces.
fn merge(base: &mut toml::Table, over: toml::Table) {
    for (k, v) in over {
        match (base.get_mut(&k), v) {
            (Some(toml::Value::Table(b)), toml::Value::Table(o)) => merge(b, o),
            (_, v) => {
                base.insert(k, v);
            }
        }
    }
}

/// Applies one `dotted.key=value` override to a model table ([`Assignment::parse`], then
/// [`apply_assignment`]).
pub(crate) fn apply_override(table: &mut toml::Table, arg: &str) -> Result<(), ModelError> {
    apply_as(table, &Assignment::parse(arg)?, arg)
}

/// Applies one assignment to a model table. Only existing tables can be entered (a
/// `fastening.custom` hold table is created), so a misspelt section is an error; a misspelt
/// leaf key is caught by `deny_unknown_fields`.
pub fn apply_assignment(table: &mut toml::Table, a: &Assignment) -> Result<(), ModelError> {
    apply_as(table, a, &a.to_string())
}

/// [`apply_assignment`], its errors naming the assignment as `shown`.
fn apply_as(table: &mut toml::Table, a: &Assignment, shown: &str) -> Result<(), ModelError> {
    let err = |message: &str| ModelError::Override {
        arg: shown.to_string(),
        message: message.to_string(),
    };
    if a.key.is_empty() || a.key.split('.').any(str::is_empty) {
        return Err(err("empty key"));
    }
    let parts: Vec<&str> = a.key.split('.').collect();
    let (leaf, path) = parts.split_last().expect("non-empty");
    let mut cur = table;
    let mut walked = String::new();
    for p in path {
        if !walked.is_empty() {
            walked.push('.');
        }
        walked.push_str(p);
        let custom = walked == "fastening.custom" || walked.starts_with("fastening.custom.");
        if custom && !cur.contains_key(*p) {
            cur.insert(p.to_string(), toml::Value::Table(toml::Table::new()));
        }
        cur = match cur.get_mut(*p) {
            Some(toml::Value::Table(t)) => t,
            Some(_) => return Err(err(&format!("`{walked}` is not a table"))),
            None => return Err(err(&format!("unknown section `{walked}`"))),
        };
    }
    cur.insert(leaf.to_string(), a.value.clone());
    Ok(())
}
