//! The field a problem text's TOML error is about (`ProblemError.field`): toml's error
//! carries the place (a byte span) and the message, not the key path, so the path is found
//! from the span in the text's spanned tables: the innermost key or value at the place, and
//! for a missing field the table at the place and the field's name (`hand.tau`,
//! `robust.objects[1].radius`). None where the text does not parse as TOML (a syntax
//! error is about no field) or the place is in no key.

use toml::de::{DeTable, DeValue};

/// The dotted field of `error`, an error of reading `text`.
pub fn field_of(text: &str, error: &toml::de::Error) -> Option<String> {
    let at = error.span()?.start;
    let doc = DeTable::parse(text).ok()?;
    let missing = quoted_after(error.message(), "missing field `");
    // a missing field's place is its table (a header), else the key or value at fault
    let found = in_table(doc.get_ref(), at, missing.is_some());
    match (found, missing) {
        (Some(path), Some(name)) => Some(joined(&path, name)),
        (None, Some(name)) => Some(name.to_string()),
        (path, None) => path,
    }
}

/// `message`'s text between `start` and the next backquote.
fn quoted_after<'a>(message: &'a str, start: &str) -> Option<&'a str> {
    let rest = &message[message.find(start)? + start.len()..];
    rest.split_once('`').map(|(name, _)| name)
}

/// `key` then `sub` (`a.b`, or `a[1]` for an array's item).
fn joined(key: &str, sub: &str) -> String {
    if sub.starts_with('[') {
        format!("{key}{sub}")
    } else {
        format!("{key}.{sub}")
    }
}

/// The innermost key of `table` (at any depth) whose key or value holds byte `at`
/// (`tables`: only a key whose value is a table, the place of a missing field).
fn in_table(table: &DeTable<'_>, at: usize, tables: bool) -> Option<String> {
    for (key, value) in table.iter() {
        if let Some(sub) = in_value(value.get_ref(), at, tables) {
            return Some(joined(key.get_ref(), &sub));
        }
    }
    table.iter().find_map(|(key, value)| {
        let here = key.span().contains(&at) || value.span().contains(&at);
        let kind = !tables || matches!(value.get_ref(), DeValue::Table(_));
        (here && kind).then(|| key.get_ref().to_string())
    })
}

/// The path inside `value` (a table, or an array's item) of byte `at`.
fn in_value(value: &DeValue<'_>, at: usize, tables: bool) -> Option<String> {
    match value {
        DeValue::Table(t) => in_table(t, at, tables),
        DeValue::Array(items) => {
            for (i, item) in items.iter().enumerate() {
                if let Some(sub) = in_value(item.get_ref(), at, tables) {
                    return Some(joined(&format!("[{i}]"), &sub));
                }
            }
            items.iter().enumerate().find_map(|(i, item)| {
                let kind = !tables || matches!(item.get_ref(), DeValue::Table(_));
                (item.span().contains(&at) && kind).then(|| format!("[{i}]"))
            })
        }
        _ => None,
    }
}
