//! Typed rows as columns: one column per leaf field of a row type, walked by the library's
//! CSV row walker (`gripopt::walk_row`: flattened structs by their own names, nested ones
//! as `outer.inner`, arrays as `name_0`, `name_1`, …), so a DataFrame's columns are the row
//! type's fields and a CSV file's columns, whatever fields it gains. `None`
//! is a missing value; a column knows whether its field is an `Option`, so that pandas gets
//! a nullable integer or boolean column for it even where every value is present.

use gripopt::{walk_row, CellError, Leaf, RowSink};
use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::PyList;
use serde::de::DeserializeOwned;
use serde::ser::{self, Serialize};
use std::collections::HashMap;

/// The values of one column (missing ones hold a filler: NaN, 0, false, None).
#[derive(Debug)]
enum Values {
    /// No value seen yet (only missing ones).
    Unknown,
    F64(Vec<f64>),
    I64(Vec<i64>),
    Bool(Vec<bool>),
    Text(Vec<Option<String>>),
}

/// One column.
#[derive(Debug)]
struct Column {
    name: String,
    values: Values,
    /// True where the value is missing.
    missing: Vec<bool>,
    /// The field is an `Option` (or a value was missing).
    optional: bool,
}

impl Column {
    fn len(&self) -> usize {
        self.missing.len()
    }
    fn push_missing(&mut self) {
        self.optional = true;
        self.missing.push(true);
        match &mut self.values {
            Values::Unknown => {}
            Values::F64(v) => v.push(f64::NAN),
            Values::I64(v) => v.push(0),
            Values::Bool(v) => v.push(false),
            Values::Text(v) => v.push(None),
        }
    }
}

/// A leaf value as a column holds it.
enum Value {
    F64(f64),
    I64(i64),
    Bool(bool),
    Text(String),
    Missing,
}

/// Rows gathered into columns.
#[derive(Debug, Default)]
pub struct Table {
    cols: Vec<Column>,
    index: HashMap<String, usize>,
    rows: usize,
    /// The column after the last one written (rows repeat their fields in order).
    cursor: usize,
    /// A buffer for the column names of a row's leaves.
    path: String,
}

/// A row that cannot be a table's (a map key that is not text, an enum with data, bytes).
pub type FrameError = CellError;

impl Table {
    /// The table of `rows`. A column whose values are all missing gets its field's type
    /// from the row type itself ([`Table::settle`]), so a column's dtype never depends on
    /// the values (a batch split in chunks gives the chunks' columns the same types).
    pub fn of<'a, T: Serialize + DeserializeOwned + 'a>(
        rows: impl IntoIterator<Item = &'a T>,
    ) -> Result<Self, FrameError> {
        let mut t = Table::default();
        let mut first = None;
        for r in rows {
            t.push(r)?;
            first.get_or_insert(r);
        }
        if let Some(r) = first {
            t.settle(r);
        }
        Ok(t)
    }

    /// The table of `rows`, or where there are none the columns of `template` (a row of
    /// the same table) with no values: an empty table has the columns and types a table
    /// with rows has, never a default set.
    pub fn of_or_like<'a, T: Serialize + DeserializeOwned + 'a>(
        rows: &'a [T],
        template: impl FnOnce() -> Option<T>,
    ) -> Result<Self, FrameError> {
        if !rows.is_empty() {
            return Self::of(rows);
        }
        let Some(row) = template() else { return Ok(Table::default()) };
        let mut t = Self::of([&row])?;
        for c in &mut t.cols {
            c.missing.clear();
            match &mut c.values {
                Values::Unknown => {}
                Values::F64(v) => v.clear(),
                Values::I64(v) => v.clear(),
                Values::Bool(v) => v.clear(),
                Values::Text(v) => v.clear(),
            }
        }
        t.rows = 0;
        Ok(t)
    }

    /// The type of each column that has no value yet, asked of the row type: the field
    /// of `template` set to 0.5, 1, true or "x" in turn, the first that `T` deserialises
    /// from is the field's type (a float, an integer, a boolean; text otherwise).
    fn settle<T: Serialize + DeserializeOwned>(&mut self, template: &T) {
        use serde_json::{json, Value};
        if !self.cols.iter().any(|c| matches!(c.values, Values::Unknown)) {
            return;
        }
        let Ok(Value::Object(obj)) = serde_json::to_value(template) else { return };
        for c in self.cols.iter_mut().filter(|c| matches!(c.values, Values::Unknown)) {
            if !obj.contains_key(&c.name) {
                continue;
            }
            let accepts = |v: Value| {
                let mut o = obj.clone();
                o.insert(c.name.clone(), v);
                serde_json::from_value::<T>(Value::Object(o)).is_ok()
            };
            let n = c.len();
            c.values = if accepts(json!(0.5)) {
                Values::F64(vec![f64::NAN; n])
            } else if accepts(json!(1)) {
                Values::I64(vec![0; n])
            } else if accepts(json!(true)) {
                Values::Bool(vec![false; n])
            } else {
                Values::Text(vec![None; n])
            };
        }
    }

    /// Add one row.
    pub fn push<T: Serialize + ?Sized>(&mut self, row: &T) -> Result<(), FrameError> {
        self.cursor = 0;
        let mut key = std::mem::take(&mut self.path);
        let walked = walk_row(row, self, &mut key);
        self.path = key;
        walked?;
        self.rows += 1;
        for c in &mut self.cols {
            if c.len() < self.rows {
                c.push_missing();
            }
        }
        Ok(())
    }

    /// Columns of plain numbers (named `names`, a value per name in each row), e.g. a
    /// trajectory's samples.
    pub fn of_numbers<R: AsRef<[f64]>>(names: &[&str], rows: impl Iterator<Item = R>) -> Self {
        let mut cols: Vec<Vec<f64>> = vec![Vec::new(); names.len()];
        for r in rows {
            for (c, v) in cols.iter_mut().zip(r.as_ref()) {
                c.push(*v);
            }
        }
        let rows = cols.first().map_or(0, Vec::len);
        let cols = names
            .iter()
            .zip(cols)
            .map(|(n, v)| Column {
                name: n.to_string(),
                missing: vec![false; v.len()],
                values: Values::F64(v),
                optional: false,
            })
            .collect();
        Table { cols, rows, ..Table::default() }
    }

    /// A grasp trajectory's columns (`gripopt.SAMPLE_COLUMNS`, as `simulate --csv` writes
    /// them), with finger 2's (`finger2_…`) where the samples carry them (the offset scene).
    pub fn of_samples(samples: &[gripopt::Sample]) -> Self {
        let finger2 = samples.iter().any(|s| s.finger2.is_some());
        let columns = gripopt::trajectory_columns(finger2);
        let names: Vec<&str> = columns.iter().map(|c| c.0).collect();
        Self::of_numbers(&names, samples.iter().map(|s| gripopt::trajectory_row(s, finger2)))
    }

    fn put(&mut self, key: &str, leaf: Value, optional: bool) -> Result<(), FrameError> {
        let k = match self.cols.get(self.cursor) {
            Some(c) if c.name == key => self.cursor,
            _ => match self.index.get(key) {
                Some(&k) => k,
                None => {
                    let mut c =
                        Column { name: key.to_string(), values: Values::Unknown, missing: Vec::new(), optional: false };
                    for _ in 0..self.rows {
                        c.push_missing();
                    }
                    self.index.insert(key.to_string(), self.cols.len());
                    self.cols.push(c);
                    self.cols.len() - 1
                }
            },
        };
        self.cursor = k + 1;
        let c = &mut self.cols[k];
        if c.len() > self.rows {
            return Err(ser::Error::custom(format_args!("column `{}` written twice in one row", c.name)));
        }
        c.optional |= optional;
        if let Value::Missing = leaf {
            c.push_missing();
            return Ok(());
        }
        if let Values::Unknown = c.values {
            let n = c.len();
            c.values = match &leaf {
                Value::F64(_) => Values::F64(vec![f64::NAN; n]),
                Value::I64(_) => Values::I64(vec![0; n]),
                Value::Bool(_) => Values::Bool(vec![false; n]),
                _ => Values::Text(vec![None; n]),
            };
        }
        match (&mut c.values, leaf) {
            (Values::F64(v), Value::F64(x)) => v.push(x),
            (Values::I64(v), Value::I64(x)) => v.push(x),
            (Values::Bool(v), Value::Bool(x)) => v.push(x),
            (Values::Text(v), Value::Text(x)) => v.push(Some(x)),
            _ => return Err(ser::Error::custom(format_args!("column `{}`: values of different types", c.name))),
        }
        c.missing.push(false);
        Ok(())
    }

    /// Number of rows.
    #[cfg(test)]
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// The columns for Python: `(name, kind, values, missing)` with kind `f64` (a float64
    /// array, NaN where missing), `i64` / `bool` (an int64 / bool array; `missing`, a bool
    /// array, when the field is an `Option`, else None) or `str` (a list of str or None).
    pub fn into_py(self, py: Python<'_>) -> PyResult<Bound<'_, PyList>> {
        let out = PyList::empty(py);
        for c in self.cols {
            let missing = c.optional.then(|| PyArray1::from_vec(py, c.missing.clone()).into_any());
            let (kind, values): (&str, Bound<'_, PyAny>) = match c.values {
                Values::Unknown => ("f64", PyArray1::from_vec(py, vec![f64::NAN; c.missing.len()]).into_any()),
                Values::F64(v) => ("f64", PyArray1::from_vec(py, v).into_any()),
                Values::I64(v) => ("i64", PyArray1::from_vec(py, v).into_any()),
                Values::Bool(v) => ("bool", PyArray1::from_vec(py, v).into_any()),
                Values::Text(v) => ("str", PyList::new(py, v)?.into_any()),
            };
            out.append((c.name, kind, values, missing))?;
        }
        Ok(out)
    }
}

impl RowSink for Table {
    fn leaf(&mut self, key: &str, value: Leaf<'_>, optional: bool) -> Result<(), CellError> {
        let leaf = match value {
            Leaf::Bool(v) => Value::Bool(v),
            Leaf::I64(v) => Value::I64(v),
            Leaf::U64(v) => Value::I64(
                i64::try_from(v).map_err(|_| ser::Error::custom(format_args!("`{key}` = {v}: beyond int64")))?,
            ),
            Leaf::F64(v) => Value::F64(v),
            Leaf::Char(c) => Value::Text(c.to_string()),
            Leaf::Str(v) | Leaf::Variant(v) => Value::Text(v.to_string()),
            // a pre-quoted cell: `"text"`, `""` = none
            Leaf::Raw(v) => {
                let text = v.strip_prefix('"').and_then(|s| s.strip_suffix('"')).unwrap_or(v);
                let leaf = if text.is_empty() { Value::Missing } else { Value::Text(text.to_string()) };
                return self.put(key, leaf, true);
            }
            Leaf::Missing => Value::Missing,
        };
        self.put(key, leaf, optional)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde::Serialize;

    #[derive(Serialize, serde::Deserialize)]
    struct Inner {
        a: f64,
        b: Option<u8>,
    }
    #[derive(Serialize, serde::Deserialize)]
    struct Row {
        id: u64,
        #[serde(flatten)]
        inner: Inner,
        pair: [f64; 2],
        name: Option<String>,
        ok: Option<bool>,
        nested: Inner,
    }

    #[test]
    fn a_trajectory_has_finger_2s_columns_where_its_samples_do() {
        let p = gripopt::Problem::load(concat!(env!("CARGO_MANIFEST_DIR"), "/../../problems/bottle-1l.toml")).unwrap();
        let names = |scene| {
            let req = gripopt::SimulateRequest { scene, ..Default::default() };
            let sim = gripopt::simulate(&p, &p.nominal, &req).unwrap();
            let t = Table::of_samples(&sim.trajectory.samples);
            assert!(t.rows() > 100 && t.cols.iter().all(|c| c.len() == t.rows()));
            t.cols.iter().map(|c| c.name.clone()).collect::<Vec<_>>()
        };
        let centred = names(None);
        assert_eq!(centred, gripopt::SAMPLE_COLUMNS.map(|c| c.0));
        let offset = names(Some(gripopt::SceneChoice::parse("offset:0.002").unwrap()));
        assert_eq!(offset[..16], centred[..]);
        assert_eq!(offset[16..], gripopt::FINGER2_COLUMNS.map(|c| c.0));
    }

    #[test]
    fn rows_become_typed_columns() {
        let rows = [
            Row {
                id: 1,
                inner: Inner { a: 0.5, b: None },
                pair: [1.0, 2.0],
                name: None,
                ok: Some(true),
                nested: Inner { a: 1.0, b: Some(3) },
            },
            Row {
                id: 2,
                inner: Inner { a: 1.5, b: Some(7) },
                pair: [3.0, 4.0],
                name: Some("x".into()),
                ok: None,
                nested: Inner { a: 2.0, b: None },
            },
        ];
        let t = Table::of(&rows).unwrap();
        let names: Vec<&str> = t.cols.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(names, ["id", "a", "b", "pair_0", "pair_1", "name", "ok", "nested.a", "nested.b"]);
        assert_eq!(t.rows(), 2);
        let col = |n: &str| t.cols.iter().find(|c| c.name == n).unwrap();
        assert!(matches!(&col("id").values, Values::I64(v) if v == &[1, 2]) && !col("id").optional);
        assert!(matches!(&col("b").values, Values::I64(v) if v == &[0, 7]) && col("b").optional);
        assert_eq!(col("b").missing, [true, false]);
        assert!(matches!(&col("name").values, Values::Text(v) if v == &[None, Some("x".to_string())]));
        assert!(
            matches!(&col("ok").values, Values::Bool(v) if v == &[true, false]) && col("ok").missing == [false, true]
        );
        assert!(matches!(&col("pair_1").values, Values::F64(v) if v == &[2.0, 4.0]));
        // a column without any value gets its field's type from the row type
        let none = Row {
            id: 3,
            inner: Inner { a: 0.0, b: None },
            pair: [0.0; 2],
            name: None,
            ok: None,
            nested: Inner { a: 0.0, b: None },
        };
        let t = Table::of(&[none]).unwrap();
        let col = |n: &str| t.cols.iter().find(|c| c.name == n).unwrap();
        assert!(matches!(col("b").values, Values::I64(_)) && col("b").optional);
        assert!(matches!(col("ok").values, Values::Bool(_)));
        assert!(matches!(col("name").values, Values::Text(_)));
    }
}
