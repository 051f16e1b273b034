//! Format-preserving edits of the library manifest (toml_edit): list an entry's fields and
//! set one value, keeping every comment, blank line and the order of keys. Pure: text in,
//! text out; the caller validates the result with the manifest parser.

use toml_edit::{DocumentMut, Item, Value};

/// One editable field of an entry: its key and its value as TOML text.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Field {
    /// The key.
    pub key: String,
    /// The value as it reads in the file (without surrounding comments).
    pub value: String,
}

fn parse(text: &str) -> Result<DocumentMut, String> {
    text.parse::<DocumentMut>().map_err(|e| format!("the manifest is not valid TOML: {e}"))
}

/// Whether `text` reads as TOML; what is wrong and where, on one line, when not (an edit
/// applied to a file that does not read would find none of its entries).
pub fn readable(text: &str) -> Result<(), String> {
    text.parse::<DocumentMut>().map(|_| ()).map_err(|e| {
        let message = e.to_string();
        let lines: Vec<&str> = message.lines().map(str::trim).filter(|l| !l.is_empty()).collect();
        let (first, last) = (lines.first().copied().unwrap_or(""), lines.last().copied().unwrap_or(""));
        if first == last { first.to_string() } else { format!("{first}: {last}") }
    })
}

/// The fields of the `[[exemplar]]` named `name`, then those of its steps as
/// `steps[i].KEY`.
pub fn fields(text: &str, name: &str) -> Result<Vec<Field>, String> {
    let doc = parse(text)?;
    let table = entry(&doc, name)?;
    let values = |t: &toml_edit::Table, prefix: &str| -> Vec<Field> {
        t.iter()
            .filter_map(|(k, item)| {
                item.as_value().map(|v| Field { key: format!("{prefix}{k}"), value: v.to_string().trim().to_string() })
            })
            .collect()
    };
    let mut out = values(table, "");
    if let Some(steps) = table.get("steps").and_then(Item::as_array_of_tables) {
        for (i, step) in steps.iter().enumerate() {
            out.extend(values(step, &format!("steps[{i}].")));
        }
    }
    Ok(out)
}

/// Splits `steps[3].count` into (Some(3), "count"); a plain key into (None, key).
fn step_key(key: &str) -> (Option<usize>, &str) {
    let parsed =
        key.strip_prefix("steps[").and_then(|rest| rest.split_once("].")).and_then(|(i, k)| Some((i.parse().ok()?, k)));
    match parsed {
        Some((i, k)) => (Some(i), k),
        None => (None, key),
    }
}

fn entry<'a>(doc: &'a DocumentMut, name: &str) -> Result<&'a toml_edit::Table, String> {
    let list =
        doc.get("exemplar").and_then(Item::as_array_of_tables).ok_or("the manifest has no [[exemplar]] entries")?;
    list.iter()
        .find(|t| t.get("name").and_then(Item::as_str) == Some(name))
        .ok_or_else(|| format!("no exemplar named {name:?} in the manifest"))
}

fn entry_mut<'a>(doc: &'a mut DocumentMut, name: &str) -> Result<&'a mut toml_edit::Table, String> {
    let list = doc
        .get_mut("exemplar")
        .and_then(Item::as_array_of_tables_mut)
        .ok_or("the manifest has no [[exemplar]] entries")?;
    list.iter_mut()
        .find(|t| t.get("name").and_then(Item::as_str) == Some(name))
        .ok_or_else(|| format!("no exemplar named {name:?} in the manifest"))
}

/// The manifest with a copy of exemplar `name` right after it (and its steps), named
/// `NAME-2` (or the first free `NAME-k`), and that name. Comments above the entry are not
/// copied; everything else stays as it was.
pub fn duplicate(text: &str, name: &str) -> Result<(String, String), String> {
    let mut doc = parse(text)?;
    let list = doc
        .get_mut("exemplar")
        .and_then(Item::as_array_of_tables_mut)
        .ok_or("the manifest has no [[exemplar]] entries")?;
    let taken = |n: &str| list.iter().any(|t| t.get("name").and_then(Item::as_str) == Some(n));
    let copy_name = (2..).map(|k| format!("{name}-{k}")).find(|n| !taken(n)).expect("a free name");
    let index = list
        .iter()
        .position(|t| t.get("name").and_then(Item::as_str) == Some(name))
        .ok_or_else(|| format!("no exemplar named {name:?} in the manifest"))?;
    let mut copy = list.get(index).expect("found above").clone();
    // no position: the copy is written where it stands in the list, after the original
    copy.set_position(None);
    copy.decor_mut().set_prefix("\n");
    if let Some(steps) = copy.get_mut("steps").and_then(Item::as_array_of_tables_mut) {
        steps.iter_mut().for_each(|t| t.set_position(None));
    }
    copy.insert("name", toml_edit::value(copy_name.as_str()));
    list.insert(index + 1, copy);
    Ok((doc.to_string(), copy_name))
}

/// The manifest with a new exemplar at the end, made by `recipe` from `file` (a path as
/// written in the manifest; kinds that read none get `None`), with the settings a first
/// build wants; and its name: the file's stem or the recipe's name, made allowed and free.
pub fn new_entry(text: &str, recipe: &str, file: Option<&str>) -> Result<(String, String), String> {
    let mut doc = parse(text)?;
    // In a manifest without entries, its comments are the document's trailer: keep them above.
    let first = doc.get("exemplar").is_none();
    let header = if first { doc.trailing().as_str().unwrap_or("").to_string() } else { String::new() };
    if first {
        doc.set_trailing("");
    }
    let list = doc
        .entry("exemplar")
        .or_insert(Item::ArrayOfTables(toml_edit::ArrayOfTables::new()))
        .as_array_of_tables_mut()
        .ok_or("exemplar is not a list of [[exemplar]] tables")?;
    let stem = file.and_then(|f| std::path::Path::new(f).file_stem()).map(|s| s.to_string_lossy().to_string());
    let hint = stem.unwrap_or_else(|| recipe.trim_start_matches("procedural:").to_string());
    let hint = allowed_name(&hint);
    let taken = |n: &str| list.iter().any(|t| t.get("name").and_then(Item::as_str) == Some(n));
    let name = std::iter::once(hint.clone())
        .chain((2..).map(|k| format!("{hint}-{k}")))
        .find(|n| !taken(n))
        .expect("a free name");
    let mut t = toml_edit::Table::new();
    t.insert("name", toml_edit::value(name.as_str()));
    t.insert("recipe", toml_edit::value(recipe));
    let file_key = if recipe == "load" { "volume" } else { "image" };
    if let Some(file) = file {
        t.insert(file_key, toml_edit::value(file));
    }
    match recipe {
        "synth" | "synth-layered" => {
            t.insert("max_exemplar", toml_edit::value(128));
            t.insert("size", toml_edit::value(64));
        }
        "sweep" => {
            t.insert("length", toml_edit::value(64));
            t.insert("axis", toml_edit::value("x"));
        }
        "load" => {}
        _ => {
            t.insert("size", toml_edit::value(64));
        }
    }
    if recipe != "load" {
        t.insert("seed", toml_edit::value(1));
    }
    t.decor_mut().set_prefix(format!("{header}\n"));
    list.push(t);
    Ok((doc.to_string(), name))
}

/// `text` as a name the manifest allows: ASCII letters, digits and `_` kept, each run of
/// anything else one `-`, no `-` at either end (a name starting with one would read as an
/// option on the command line); `exemplar` when nothing is left.
fn allowed_name(text: &str) -> String {
    let mut out = String::new();
    for c in text.chars() {
        if c.is_ascii_alphanumeric() || c == '_' {
            out.push(c);
        } else if !out.ends_with('-') {
            out.push('-');
        }
    }
    let out = out.trim_matches('-');
    if out.chars().any(|c| c.is_ascii_alphanumeric()) { out.to_string() } else { "exemplar".to_string() }
}

/// The manifest without exemplar `name` (and the comments right above it; the first
/// entry's lines above it, the file's header, stay).
pub fn delete(text: &str, name: &str) -> Result<String, String> {
    let mut doc = parse(text)?;
    let list = doc
        .get_mut("exemplar")
        .and_then(Item::as_array_of_tables_mut)
        .ok_or("the manifest has no [[exemplar]] entries")?;
    let named = |t: &toml_edit::Table| t.get("name").and_then(Item::as_str) == Some(name);
    let index = list.iter().position(named).ok_or_else(|| format!("no exemplar named {name:?} in the manifest"))?;
    if list.iter().filter(|t| named(t)).count() > 1 {
        // an undo finds the entry by name, and could not tell which one to put back
        return Err(format!(
            "the manifest has more than one exemplar named {name:?}; rename one in a text editor first, then delete"
        ));
    }
    let removed = list.remove(index);
    if index == 0
        && let Some(next) = list.get_mut(0)
    {
        let header = removed.decor().prefix().and_then(|p| p.as_str()).unwrap_or("").to_string();
        next.decor_mut().set_prefix(header);
    }
    if list.is_empty() {
        doc.remove("exemplar");
    }
    Ok(doc.to_string())
}

/// The manifest with exemplar `name` renamed `new` (its comments and layout kept). Refused:
/// a name the manifest does not allow (ASCII letters, digits, '-' and '_') or one taken.
pub fn rename(text: &str, name: &str, new: &str) -> Result<String, String> {
    if new.is_empty() || !new.chars().all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_') {
        return Err(format!("{new:?} is not a name the manifest allows: use ASCII letters, digits, '-' and '_'"));
    }
    if new != name && fields(text, new).is_ok() {
        return Err(format!("the manifest already has an exemplar named {new:?}"));
    }
    set(text, name, "name", &format!("{new:?}"))
}

/// Which step a field key such as `steps[2].count` belongs to.
pub fn step_of(key: &str) -> Option<usize> {
    step_key(key).0
}

fn steps_mut<'a>(doc: &'a mut DocumentMut, name: &str) -> Result<&'a mut toml_edit::ArrayOfTables, String> {
    entry_mut(doc, name)?
        .get_mut("steps")
        .and_then(Item::as_array_of_tables_mut)
        .ok_or_else(|| format!("{name} has no [[exemplar.steps]]"))
}

/// The manifest without step `index` of exemplar `name` (and the comments right above it).
pub fn remove_step(text: &str, name: &str, index: usize) -> Result<String, String> {
    let mut doc = parse(text)?;
    let steps = steps_mut(&mut doc, name)?;
    if index >= steps.len() {
        return Err(format!("{name} has no step {index}"));
    }
    steps.remove(index);
    if steps.is_empty() {
        entry_mut(&mut doc, name)?.remove("steps");
    }
    Ok(doc.to_string())
}

/// The manifest with step `index` of exemplar `name` swapped with the one before it
/// (`earlier`) or after it, each with its comments; and the step's new index.
pub fn move_step(text: &str, name: &str, index: usize, earlier: bool) -> Result<(String, usize), String> {
    let mut doc = parse(text)?;
    let steps = steps_mut(&mut doc, name)?;
    let other = if earlier { index.checked_sub(1) } else { Some(index + 1) };
    let Some(other) = other.filter(|o| *o < steps.len() && index < steps.len()) else {
        let end = if earlier { "first" } else { "last" };
        return Err(format!("step {index} of {name} is already the {end}"));
    };
    let (lo, hi) = (index.min(other), index.max(other));
    let (first, second) = (steps.get(lo).expect("in range").clone(), steps.get(hi).expect("in range").clone());
    // tables are written in the order of their positions: the two trade places and positions
    let (mut moved_up, mut moved_down) = (second, first);
    let (p_lo, p_hi) = (moved_down.position(), moved_up.position());
    moved_up.set_position(p_lo);
    moved_down.set_position(p_hi);
    steps.replace(lo, moved_up);
    steps.replace(hi, moved_down);
    Ok((doc.to_string(), other))
}

/// The manifest with `key` of exemplar `name` set to the TOML value `value` (a new key is
/// appended). Everything else — comments, spacing, order — stays as it was.
pub fn set(text: &str, name: &str, key: &str, value: &str) -> Result<String, String> {
    let parsed: Value = value
        .trim()
        .parse()
        .map_err(|_| format!("{key} = {value}: not a TOML value (quote text: \"...\"; numbers and [lists] as is)"))?;
    let mut doc = parse(text)?;
    let entry = entry_mut(&mut doc, name)?;
    let (step, key) = step_key(key);
    let table = match step {
        None => entry,
        Some(i) => entry
            .get_mut("steps")
            .and_then(Item::as_array_of_tables_mut)
            .and_then(|steps| steps.get_mut(i))
            .ok_or_else(|| format!("{name} has no step {i}"))?,
    };
    match table.get_mut(key).and_then(Item::as_value_mut) {
        Some(old) => {
            let decor = old.decor().clone();
            *old = parsed;
            *old.decor_mut() = decor;
        }
        None => {
            table.insert(key, toml_edit::value(parsed));
        }
    }
    Ok(doc.to_string())
}

/// The manifest without field `key` of exemplar `name` (a top-level field; steps are
/// removed whole with [`remove_step`]).
pub fn unset(text: &str, name: &str, key: &str) -> Result<String, String> {
    let mut doc = parse(text)?;
    let entry = entry_mut(&mut doc, name)?;
    entry.remove(key).ok_or_else(|| format!("{name} has no field {key}"))?;
    Ok(doc.to_string())
}

/// The line (from 1) where exemplar `name`'s `name = ...` stands, for an outside editor.
pub fn line_of(text: &str, name: &str) -> usize {
    let quoted = format!("{name:?}");
    let at = text.lines().position(|l| {
        let l = l.trim_start();
        l.starts_with("name") && l.split_once('=').is_some_and(|(k, v)| k.trim() == "name" && v.trim() == quoted)
    });
    at.map_or(1, |i| i + 1)
}

/// The manifest with `steps` appended to exemplar `name`'s `[[exemplar.steps]]`, each a
/// `stamp` or `scatter` of the seed mesh `file` in the dark seed colour.
pub fn append_steps(text: &str, name: &str, steps: &[super::model::StampStep], file: &str) -> Result<String, String> {
    append_tables(text, name, steps.iter().map(|step| step_table(step, file)).collect())
}

/// The manifest with a blur step appended to exemplar `name`: inside the sphere at voxel
/// `at` of radius `radius` voxels.
pub fn append_blur(text: &str, name: &str, at: [f32; 3], radius: f32) -> Result<String, String> {
    let mut t = toml_edit::Table::new();
    t.insert("blur", toml_edit::value(format!("{},{},{}", at[0], at[1], at[2])));
    let radius =
        if radius.fract() == 0.0 { toml_edit::value(radius as i64) } else { toml_edit::value(f64::from(radius)) };
    t.insert("radius", radius);
    append_tables(text, name, vec![t])
}

/// The manifest with `tables` appended to exemplar `name`'s steps, indented like its last
/// step (or by two spaces).
fn append_tables(text: &str, name: &str, tables: Vec<toml_edit::Table>) -> Result<String, String> {
    let mut doc = parse(text)?;
    let table = entry_mut(&mut doc, name)?;
    let existing = table.entry("steps").or_insert(Item::ArrayOfTables(toml_edit::ArrayOfTables::new()));
    let array = existing.as_array_of_tables_mut().ok_or("steps is not a list of [[exemplar.steps]] tables")?;
    let indent = array.iter().last().map_or_else(|| "  ".to_string(), step_indent);
    for mut table in tables {
        table.decor_mut().set_prefix(indent.clone());
        let keys: Vec<String> = table.iter().map(|(k, _)| k.to_string()).collect();
        for key in keys {
            if let Some(mut k) = table.key_mut(&key) {
                k.leaf_decor_mut().set_prefix(indent.clone());
            }
        }
        array.push(table);
    }
    Ok(doc.to_string())
}

/// The indentation of an existing step's first key (the library indents its steps by two
/// spaces), so appended steps line up with it.
fn step_indent(table: &toml_edit::Table) -> String {
    let prefix = table.iter().next().and_then(|(k, _)| {
        let key = table.key(k)?;
        key.leaf_decor().prefix().and_then(|p| p.as_str()).map(str::to_string)
    });
    let prefix = prefix.unwrap_or_default();
    prefix.rsplit('\n').next().unwrap_or("").chars().filter(|c| *c == ' ' || *c == '\t').collect()
}

fn step_table(step: &super::model::StampStep, file: &str) -> toml_edit::Table {
    use super::model::StampStep;
    let mut t = toml_edit::Table::new();
    let colour = super::stamping::SEED_COLOUR.map(|c| format!("{:02x}", (c * 255.0).round() as u8)).concat();
    match step {
        StampStep::Stamp(p) => {
            let (axis, angle) = p.rotation.to_axis_angle();
            t.insert("stamp", toml_edit::value(file));
            t.insert("at", toml_edit::value(format!("{:.1},{:.1},{:.1}", p.at.x, p.at.y, p.at.z)));
            t.insert(
                "rotate",
                toml_edit::value(format!("{:.4},{:.4},{:.4},{:.2}", axis.x, axis.y, axis.z, angle.to_degrees())),
            );
            t.insert("scale", toml_edit::value(format!("{:.4}", p.scale.x)));
        }
        StampStep::Scatter { count, scale, seed } => {
            t.insert("scatter", toml_edit::value(file));
            t.insert("count", toml_edit::value(*count as i64));
            t.insert("scale", toml_edit::value(format!("{:.2}..{:.2}", scale.0, scale.1)));
            t.insert("seed", toml_edit::value(*seed as i64));
        }
    }
    t.insert("color", toml_edit::value(format!("#{colour}")));
    t
}

/// The bytes of exemplar `name`'s block in `text`: from its `[[exemplar]]` header through
/// its last line that is not blank or a comment, its steps included (the comments above the
/// next entry belong to that one). None when the text does not parse or has no entry, or
/// two, of that name.
fn block(text: &str, name: &str) -> Option<std::ops::Range<usize>> {
    let doc = toml_edit::Document::parse(text).ok()?;
    let list = doc.get("exemplar")?.as_array_of_tables()?;
    let mut found = list.iter().filter(|t| t.get("name").and_then(Item::as_str) == Some(name));
    let start = found.next()?.span()?.start;
    if found.next().is_some() {
        return None;
    }
    // Every top-level header: the entries' and any other table's.
    let headers = doc.iter().flat_map(|(_, item)| match item {
        Item::Table(t) => t.span().into_iter().collect::<Vec<_>>(),
        Item::ArrayOfTables(a) => a.iter().filter_map(toml_edit::Table::span).collect(),
        _ => Vec::new(),
    });
    let end = headers.map(|s| s.start).filter(|s| *s > start).min().unwrap_or(text.len());
    let mut last = start;
    let mut at = start;
    for line in text[start..end].split_inclusive('\n') {
        at += line.len();
        let t = line.trim();
        if !t.is_empty() && !t.starts_with('#') {
            last = at;
        }
    }
    Some(start..last)
}

/// `target` with exemplar `name`'s block taken from `source` (appended when `target` has
/// no such entry); None when `source` has none. The designer's "keep mine" when both
/// changed the entry.
pub fn with_entry_of(source: &str, target: &str, name: &str) -> Option<String> {
    let piece = &source[block(source, name)?];
    Some(match block(target, name) {
        Some(range) => format!("{}{piece}{}", &target[..range.start], &target[range.end..]),
        None if target.is_empty() || target.ends_with("\n\n") => format!("{target}{piece}\n"),
        None if target.ends_with('\n') => format!("{target}\n{piece}\n"),
        None => format!("{target}\n\n{piece}\n"),
    })
}

/// The editor's text `mine` (edits of exemplar `name` made on `base`) applied to `theirs`,
/// the manifest as it reads now: their changes elsewhere are kept and the entry is mine.
/// None when both changed the entry (the designer chooses).
pub fn rebase(base: &str, mine: &str, theirs: &str, name: &str) -> Option<String> {
    if theirs == base {
        return Some(mine.to_string());
    }
    let piece = |t: &str| block(t, name).map(|r| t[r].to_string());
    let (before, mine_piece, theirs_piece) = (piece(base), piece(mine), piece(theirs));
    if mine_piece == before {
        Some(theirs.to_string())
    } else if theirs_piece == before {
        with_entry_of(mine, theirs, name)
    } else {
        None
    }
}

/// What deleting an entry removed, to put it back where it was (see [`restore`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Removed {
    /// The entry's name.
    pub name: String,
    /// The bytes removed: the entry, its steps and the comments above it.
    pub chunk: String,
    /// The entry before it (None: it was the first).
    pub after: Option<String>,
    /// The bytes between the end of that entry (or the file's start) and the chunk.
    pub gap: String,
}

/// What turned `old` into `new` by deleting exemplar `name`.
pub fn removed(old: &str, new: &str, name: &str) -> Removed {
    let prefix = old.bytes().zip(new.bytes()).take_while(|(a, b)| a == b).count();
    let room = new.len() - prefix;
    let suffix = old.bytes().rev().zip(new.bytes().rev()).take(room).take_while(|(a, b)| a == b).count();
    let (mut start, mut end) = (prefix, old.len() - suffix);
    // The same removal can sit anywhere along a run of repeated bytes (entries that end
    // alike): slide it as far up as it goes, then down to the last place, not past the
    // entry's own header, where it starts a line, so it goes back whole and the entry
    // above keeps its lines.
    let bytes = old.as_bytes();
    while start > 0 && bytes[start - 1] == bytes[end - 1] {
        (start, end) = (start - 1, end - 1);
    }
    let header = block(old, name).map_or(old.len(), |r| r.start);
    let starts_line = |i: usize| i == 0 || bytes[i - 1] == b'\n';
    let mut chosen = None;
    loop {
        if starts_line(start) && start <= header {
            chosen = Some((start, end));
        }
        if end >= old.len() || bytes[start] != bytes[end] || start >= header {
            break;
        }
        (start, end) = (start + 1, end + 1);
    }
    (start, end) = chosen.unwrap_or((start, end));
    let names = super::entry_names_of(old);
    let after = names.iter().position(|n| n == name).and_then(|i| i.checked_sub(1)).map(|i| names[i].clone());
    let anchor = after.as_deref().and_then(|a| block(old, a)).map_or(0, |r| r.end).min(start);
    Removed { name: name.to_string(), chunk: old[start..end].to_string(), after, gap: old[anchor..start].to_string() }
}

/// `text` with a deleted entry put back after the entry it followed (at the end when that
/// one is gone): the inverse of a deletion, applied to the manifest as it reads now.
/// Refused when an entry of that name is there again.
pub fn restore(text: &str, removed: &Removed) -> Result<String, String> {
    if block(text, &removed.name).is_some() || super::entry_names_of(text).contains(&removed.name) {
        return Err(format!("the manifest has an exemplar named {:?} again; nothing restored", removed.name));
    }
    let anchor = match &removed.after {
        Some(after) => block(text, after).map(|r| r.end),
        None => Some(0),
    };
    // Before the first entry when the file's top changed; at the end when the entry it
    // followed is gone.
    let first = || super::entry_names_of(text).first().and_then(|n| block(text, n)).map_or(text.len(), |r| r.start);
    let at = match anchor {
        Some(at) if text[at..].starts_with(&removed.gap) => at + removed.gap.len(),
        Some(_) if removed.after.is_none() => first(),
        Some(at) => at,
        None if text.is_empty() || text.ends_with('\n') => text.len(),
        None => return Ok(format!("{text}\n{}", removed.chunk)),
    };
    Ok(format!("{}{}{}", &text[..at], removed.chunk, &text[at..]))
}

/// Exemplar `name` as `text` has it (for showing two versions side by side).
pub fn entry_text(text: &str, name: &str) -> Option<String> {
    block(text, name).map(|r| text[r].to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An edit of entry a is applied to the file as another program left it: their new
    /// comment, their change to b and their new entry stay, and a is the editor's; when
    /// both changed a, there is no silent merge.
    #[test]
    fn an_edit_is_applied_to_the_file_as_changed_outside() {
        let mine = set(TEXT, "a", "size", "32").unwrap();
        let mine = append_blur(&mine, "a", [4.0, 4.0, 4.0], 2.0).unwrap();
        let theirs = format!(
            "{}\n# added by hand\n[[exemplar]]\nname = \"c\"\nrecipe = \"procedural:wood\"\nsize = 16\n",
            TEXT.replace("# the library", "# the library, notes").replace("size = 32", "size = 48")
        );
        let merged = rebase(TEXT, &mine, &theirs, "a").unwrap();
        assert!(merged.starts_with("# the library, notes"), "{merged}");
        let size = |name: &str| fields(&merged, name).unwrap().into_iter().find(|f| f.key == "size").unwrap().value;
        assert_eq!((size("a"), size("b"), size("c")), ("32".to_string(), "48".to_string(), "16".to_string()));
        assert!(fields(&merged, "a").unwrap().iter().any(|f| f.key == "steps[0].blur"), "{merged}");
        assert!(merged.contains("# added by hand") && merged.contains("name = \"a\"   # first"), "{merged}");
        assert_eq!(rebase(TEXT, &mine, TEXT, "a").as_deref(), Some(mine.as_str()), "nothing changed outside");
        assert_eq!(rebase(TEXT, TEXT, &theirs, "a").as_deref(), Some(theirs.as_str()), "nothing changed here");
        let both = TEXT.replace("size = 64", "size = 128");
        assert_eq!(rebase(TEXT, &mine, &both, "a"), None, "both changed a");
        let kept = with_entry_of(&mine, &both, "a").unwrap();
        assert_eq!(entry_text(&kept, "a"), entry_text(&mine, "a"));
        assert_eq!(entry_text(&kept, "b"), entry_text(&both, "b"));
        let gone = delete(TEXT, "a").unwrap();
        for name in ["a", "b"] {
            let deleted = delete(TEXT, name).unwrap();
            let what = removed(TEXT, &deleted, name);
            assert_eq!(restore(&deleted, &what).unwrap(), TEXT, "{name} is back byte for byte");
            let changed = deleted.replace("# the library", "# the library, notes");
            assert_eq!(restore(&changed, &what).unwrap(), TEXT.replace("# the library", "# the library, notes"));
            assert!(restore(TEXT, &what).unwrap_err().contains("again"));
        }
        let back = with_entry_of(&mine, &gone, "a").unwrap();
        assert_eq!(entry_text(&back, "a"), entry_text(&mine, "a"), "an entry deleted outside comes back at the end");
    }

    /// Entries that end alike (the same last field, a blank line between): a deleted one
    /// comes back byte for byte, in its place, and the one above keeps its fields.
    #[test]
    fn a_deletion_among_entries_that_end_alike_is_undone_exactly() {
        let entry = |name: &str, recipe: &str| {
            format!("[[exemplar]]\nname = \"{name}\"\nrecipe = \"procedural:{recipe}\"\nsize = 32\n")
        };
        let text = [entry("a", "marble"), entry("b", "wood"), entry("c", "strata")].join("\n");
        let library = include_str!("../../exemplars/library.toml");
        let plain = ["a", "b", "c"].map(String::from).to_vec();
        for (text, names) in [(text.as_str(), plain), (library, super::super::entry_names_of(library))] {
            for name in names.iter().map(String::as_str) {
                let deleted = delete(text, name).unwrap();
                let what = removed(text, &deleted, name);
                assert!(what.chunk.contains(&format!("name = \"{name}\"")), "{name}: {what:?}");
                assert_eq!(restore(&deleted, &what).unwrap(), text, "{name} is back byte for byte");
            }
        }
    }

    const TEXT: &str = "# the library\n\n[[exemplar]]\nname = \"a\"   # first\nrecipe = \"procedural:marble\"\nsize = 64\n\n[[exemplar]]\nname = \"b\"\nrecipe = \"procedural:strata\"\nsize = 32\n  [[exemplar.steps]]\n  blur = \"1,1,1\"\n  radius = 2\n";

    #[test]
    fn fields_are_listed_per_entry() {
        let f = fields(TEXT, "b").unwrap();
        let keys: Vec<&str> = f.iter().map(|f| f.key.as_str()).collect();
        assert_eq!(keys, ["name", "recipe", "size", "steps[0].blur", "steps[0].radius"]);
        assert_eq!(f[2].value, "32");
        assert!(fields(TEXT, "zz").unwrap_err().contains("zz"));
    }

    #[test]
    fn setting_a_value_keeps_comments_and_layout() {
        let out = set(TEXT, "a", "size", "48").unwrap();
        assert_eq!(out, TEXT.replace("size = 64", "size = 48"));
        let out = set(TEXT, "a", "name", "\"c\"").unwrap();
        assert!(out.contains("name = \"c\"   # first"), "{out}");
        let out = set(TEXT, "b", "seed", "7").unwrap();
        assert!(out.contains("size = 32\nseed = 7\n") && out.contains("# the library"), "{out}");
        assert!(set(TEXT, "a", "size", "sixty").unwrap_err().contains("not a TOML value"));
        let out = set(TEXT, "b", "steps[0].radius", "5").unwrap();
        assert_eq!(out, TEXT.replace("radius = 2", "radius = 5"));
        assert!(set(TEXT, "b", "steps[3].radius", "5").unwrap_err().contains("no step 3"));
    }

    #[test]
    fn stamps_become_steps_the_manifest_accepts() {
        use crate::stamp::Placement;
        use crate::tui::model::StampStep;
        let placement = Placement {
            at: glam::Vec3::new(10.0, 12.0, 14.0),
            rotation: glam::Quat::from_rotation_z(0.5),
            scale: glam::Vec3::splat(3.0),
        };
        let steps = [StampStep::Stamp(placement), StampStep::Scatter { count: 10, scale: (2.0, 3.0), seed: 4 }];
        let out = append_steps(TEXT, "b", &steps, "seed.obj").unwrap();
        assert!(out.starts_with("# the library") && out.contains("  blur = \"1,1,1\""), "{out}");
        assert!(
            out.contains("\n  [[exemplar.steps]]\n  stamp = \"seed.obj\"\n  at = "),
            "indented like b's step: {out}"
        );
        assert!(out.contains("\n  scatter = \"seed.obj\"\n  count = 10\n"), "{out}");
        let plan = crate::io::manifest::parse_plan(&out, std::path::Path::new("lib")).unwrap();
        let b = &plan.entries[1];
        assert_eq!(b.steps.len(), 3);
        let crate::io::manifest::Step::Stamp { placement: p, .. } = &b.steps[1] else { panic!("a stamp step") };
        assert!((p.at - placement.at).length() < 0.01 && (p.rotation.dot(placement.rotation).abs() - 1.0).abs() < 1e-4);
        assert!(matches!(b.steps[2], crate::io::manifest::Step::Scatter { count: 10, seed: 4, .. }));
        let out = append_steps(TEXT, "a", &steps[..1], "seed.obj").unwrap();
        assert_eq!(
            crate::io::manifest::parse_plan(&out, std::path::Path::new("lib")).unwrap().entries[0].steps.len(),
            1
        );
    }

    #[test]
    fn a_duplicate_follows_its_original_and_a_deletion_keeps_the_rest() {
        let (out, name) = duplicate(TEXT, "a").unwrap();
        assert_eq!(name, "a-2");
        let a = out.find("name = \"a\"").unwrap();
        let copy = out.find("name = \"a-2\"").unwrap();
        let b = out.find("name = \"b\"").unwrap();
        assert!(a < copy && copy < b, "{out}");
        assert_eq!(out.matches("# the library").count(), 1, "{out}");
        assert_eq!(fields(&out, "a-2").unwrap().len(), fields(&out, "a").unwrap().len());
        // b's steps come along, and a second copy takes the next free name
        let (out, name) = duplicate(&out, "b").unwrap();
        assert_eq!(name, "b-2");
        assert_eq!(fields(&out, "b-2").unwrap(), {
            let mut f = fields(TEXT, "b").unwrap();
            f[0].value = "\"b-2\"".into();
            f
        });
        assert_eq!(duplicate(&out, "a").unwrap().1, "a-3");
        let plan = crate::io::manifest::parse_plan(&out, std::path::Path::new("lib")).unwrap();
        assert_eq!(plan.entries.iter().map(|e| e.name.as_str()).collect::<Vec<_>>(), ["a", "a-2", "b", "b-2"]);
        // deleting: the others and the file's header stay, byte for byte
        assert_eq!(delete(&out, "a-2").unwrap(), duplicate(TEXT, "b").unwrap().0);
        let without_a = delete(TEXT, "a").unwrap();
        assert!(without_a.starts_with("# the library\n\n[[exemplar]]\nname = \"b\""), "{without_a}");
        assert!(delete(TEXT, "zz").unwrap_err().contains("zz"));
        assert!(duplicate(TEXT, "zz").unwrap_err().contains("zz"));
        // a name two entries share is not deleted: an undo could not tell which to restore
        let twice = format!("{TEXT}\n[[exemplar]]\nname = \"a\"\nrecipe = \"procedural:wood\"\nsize = 8\n");
        assert!(delete(&twice, "a").unwrap_err().contains("more than one exemplar named \"a\""));
    }

    #[test]
    fn a_rename_changes_only_the_name() {
        let out = rename(TEXT, "a", "a_new-1").unwrap();
        assert_eq!(out, TEXT.replacen("name = \"a\"", "name = \"a_new-1\"", 1));
        assert!(rename(TEXT, "a", "b").unwrap_err().contains("already has an exemplar named \"b\""));
        for bad in ["", "a b", "ä", "a/b"] {
            assert!(rename(TEXT, "a", bad).unwrap_err().contains("not a name the manifest allows"), "{bad:?}");
        }
        assert!(rename(TEXT, "zz", "y").unwrap_err().contains("zz"));
        assert_eq!(rename(TEXT, "a", "a").unwrap(), TEXT);
    }

    #[test]
    fn steps_are_removed_and_reordered_with_their_comments() {
        let text = TEXT.to_string() + "  # the second\n  [[exemplar.steps]]\n  blur = \"2,2,2\"\n  radius = 3\n";
        let (moved, at) = move_step(&text, "b", 1, true).unwrap();
        assert_eq!(at, 0);
        let keys = |t: &str| fields(t, "b").unwrap().into_iter().map(|f| f.value).collect::<Vec<_>>();
        assert_eq!(keys(&moved)[3..], ["\"2,2,2\"", "3", "\"1,1,1\"", "2"]);
        assert!(moved.contains("  # the second\n  [[exemplar.steps]]\n  blur = \"2,2,2\""), "{moved}");
        assert!(moved.find("2,2,2").unwrap() < moved.find("1,1,1").unwrap(), "{moved}");
        assert_eq!(move_step(&moved, "b", 0, false).unwrap().0, text, "moving back gives the text back");
        assert!(move_step(&text, "b", 0, true).unwrap_err().contains("already the first"));
        assert!(move_step(&text, "b", 1, false).unwrap_err().contains("already the last"));
        let removed = remove_step(&text, "b", 0).unwrap();
        assert_eq!(keys(&removed)[3..], ["\"2,2,2\"", "3"]);
        let none = remove_step(&removed, "b", 0).unwrap();
        assert!(!none.contains("steps") && none.contains("size = 32"), "{none}");
        assert!(remove_step(TEXT, "a", 0).unwrap_err().contains("no [[exemplar.steps]]"));
        assert_eq!(step_of("steps[4].count"), Some(4));
        assert_eq!(step_of("size"), None);
    }

    #[test]
    fn a_new_entry_is_appended_valid_named_after_its_file() {
        let folder = tempfile::tempdir().unwrap();
        let photo = image::RgbImage::from_fn(16, 16, |x, y| image::Rgb([(x * 16) as u8, (y * 16) as u8, 9]));
        photo.save(folder.path().join("my photo.png")).unwrap();
        let (out, name) = new_entry(TEXT, "synth", Some("my photo.png")).unwrap();
        assert_eq!(name, "my-photo");
        for (file, expected) in
            [("my bark (copy) é.png", "my-bark-copy"), ("-dash.png", "dash"), ("日本語.png", "exemplar")]
        {
            assert_eq!(new_entry(TEXT, "synth", Some(file)).unwrap().1, expected);
        }
        assert!(out.starts_with(TEXT), "the rest stays as it was:\n{out}");
        let tail = &out[TEXT.len()..];
        assert_eq!(
            tail,
            "\n[[exemplar]]\nname = \"my-photo\"\nrecipe = \"synth\"\nimage = \"my photo.png\"\nmax_exemplar = 128\nsize = 64\nseed = 1\n"
        );
        let entry = crate::io::manifest::parse_entry(&out, folder.path(), "my-photo").unwrap();
        assert!(matches!(entry.source, crate::io::manifest::Source::Synth(_)) && entry.dims == Some([64; 3]));
        // a taken name gets a number; a procedural entry is named after its recipe
        let (out, again) = new_entry(&out, "sweep", Some("my photo.png")).unwrap();
        assert_eq!(again, "my-photo-2");
        assert!(crate::io::manifest::parse_entry(&out, folder.path(), "my-photo-2").is_ok());
        let (out, wood) = new_entry(&out, "procedural:wood", None).unwrap();
        assert_eq!(wood, "wood");
        assert!(crate::io::manifest::parse_entry(&out, folder.path(), "wood").is_ok());
        // an empty manifest gets its first entry
        let (out, first) = new_entry("# mine\n", "procedural:marble", None).unwrap();
        assert!(out.starts_with("# mine\n") && first == "marble", "{out}");
        assert!(crate::io::manifest::parse_entry(&out, folder.path(), "marble").is_ok());
    }
}
