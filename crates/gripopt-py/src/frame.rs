//! Typed rows as columns, by serde: one column per leaf field of a row type (flattened
//! structs by their own names, nested ones as `outer.inner`, arrays as `name_0`, `name_1`,
//! …), so a DataFrame's columns are the row type's fields, whatever fields it gains. `None`
//! is a missing value; a column knows whether its field is an `Option`, so that pandas gets
//! a nullable integer or boolean column for it even where every value is present.

use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::PyList;
use serde::de::DeserializeOwned;
use serde::ser::{self, Impossible, Serialize};
use std::collections::HashMap;
use std::fmt::Display;

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

/// A leaf value.
enum Leaf {
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
    /// The key of the value being written.
    path: String,
}

/// A row that cannot be a table's (a map key that is not text, an enum with data, bytes).
#[derive(Debug)]
pub struct FrameError(String);

impl Display for FrameError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}
impl std::error::Error for FrameError {}
impl ser::Error for FrameError {
    fn custom<T: Display>(msg: T) -> Self {
        FrameError(msg.to_string())
    }
}

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
        self.path.clear();
        self.cursor = 0;
        row.serialize(Ser { t: self, optional: false, raw: false })?;
        self.rows += 1;
        for c in &mut self.cols {
            if c.len() < self.rows {
                c.push_missing();
            }
        }
        Ok(())
    }

    /// Columns of plain numbers (named `names`), e.g. a trajectory's samples.
    pub fn of_numbers<const N: usize>(names: &[&str; N], rows: impl Iterator<Item = [f64; N]>) -> Self {
        let mut cols: Vec<Vec<f64>> = vec![Vec::new(); N];
        for r in rows {
            for (c, v) in cols.iter_mut().zip(r) {
                c.push(v);
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

    fn put(&mut self, leaf: Leaf, optional: bool) -> Result<(), FrameError> {
        let k = match self.cols.get(self.cursor) {
            Some(c) if c.name == self.path => self.cursor,
            _ => match self.index.get(&self.path) {
                Some(&k) => k,
                None => {
                    let mut c = Column {
                        name: self.path.clone(),
                        values: Values::Unknown,
                        missing: Vec::new(),
                        optional: false,
                    };
                    for _ in 0..self.rows {
                        c.push_missing();
                    }
                    self.index.insert(self.path.clone(), self.cols.len());
                    self.cols.push(c);
                    self.cols.len() - 1
                }
            },
        };
        self.cursor = k + 1;
        let c = &mut self.cols[k];
        if c.len() > self.rows {
            return Err(FrameError(format!("column `{}` written twice in one row", c.name)));
        }
        c.optional |= optional;
        if let Leaf::Missing = leaf {
            c.push_missing();
            return Ok(());
        }
        if let Values::Unknown = c.values {
            let n = c.len();
            c.values = match &leaf {
                Leaf::F64(_) => Values::F64(vec![f64::NAN; n]),
                Leaf::I64(_) => Values::I64(vec![0; n]),
                Leaf::Bool(_) => Values::Bool(vec![false; n]),
                _ => Values::Text(vec![None; n]),
            };
        }
        match (&mut c.values, leaf) {
            (Values::F64(v), Leaf::F64(x)) => v.push(x),
            (Values::I64(v), Leaf::I64(x)) => v.push(x),
            (Values::Bool(v), Leaf::Bool(x)) => v.push(x),
            (Values::Text(v), Leaf::Text(x)) => v.push(Some(x)),
            _ => return Err(FrameError(format!("column `{}`: values of different types", c.name))),
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

/// The name serde gives gripopt's pre-quoted CSV cells (`reason`): written `"text"`, or
/// `""` for none.
const RAW_CELL: &str = "gripopt::RawCell";

/// The serializer of one value at `t.path`.
struct Ser<'a> {
    t: &'a mut Table,
    /// Inside an `Option`.
    optional: bool,
    /// A pre-quoted CSV cell.
    raw: bool,
}

/// A struct, map or sequence: each field or element at its own key.
struct Fields<'a> {
    t: &'a mut Table,
    /// The key's length before this value's fields were appended.
    base: usize,
    /// Elements so far (sequences).
    n: usize,
    optional: bool,
}

impl Fields<'_> {
    fn field<T: Serialize + ?Sized>(&mut self, name: &str, v: &T) -> Result<(), FrameError> {
        self.t.path.truncate(self.base);
        if self.base > 0 {
            self.t.path.push('.');
        }
        self.t.path.push_str(name);
        self.value(v)
    }
    /// The value of the field whose name is already in the key.
    fn value<T: Serialize + ?Sized>(&mut self, v: &T) -> Result<(), FrameError> {
        v.serialize(Ser { t: self.t, optional: self.optional, raw: false })?;
        self.t.path.truncate(self.base);
        Ok(())
    }
    fn element<T: Serialize + ?Sized>(&mut self, v: &T) -> Result<(), FrameError> {
        self.t.path.truncate(self.base);
        let n = self.n;
        self.n += 1;
        use std::fmt::Write as _;
        let _ = write!(self.t.path, "_{n}");
        v.serialize(Ser { t: self.t, optional: self.optional, raw: false })?;
        self.t.path.truncate(self.base);
        Ok(())
    }
}

impl<'a> Ser<'a> {
    fn leaf(self, l: Leaf) -> Result<(), FrameError> {
        let o = self.optional;
        self.t.put(l, o)
    }
    fn fields(self) -> Fields<'a> {
        let base = self.t.path.len();
        Fields { t: self.t, base, n: 0, optional: self.optional }
    }
}

macro_rules! ints {
    ($($f:ident $t:ty),*) => {$(
        fn $f(self, v: $t) -> Result<(), FrameError> {
            let x = i64::try_from(v).map_err(|_| FrameError(format!("`{}` = {v}: beyond int64", self.t.path)))?;
            self.leaf(Leaf::I64(x))
        }
    )*};
}

impl<'a> ser::Serializer for Ser<'a> {
    type Ok = ();
    type Error = FrameError;
    type SerializeSeq = Fields<'a>;
    type SerializeTuple = Fields<'a>;
    type SerializeTupleStruct = Fields<'a>;
    type SerializeTupleVariant = Impossible<(), FrameError>;
    type SerializeMap = Fields<'a>;
    type SerializeStruct = Fields<'a>;
    type SerializeStructVariant = Impossible<(), FrameError>;

    fn serialize_bool(self, v: bool) -> Result<(), FrameError> {
        self.leaf(Leaf::Bool(v))
    }
    ints!(serialize_i8 i8, serialize_i16 i16, serialize_i32 i32, serialize_i64 i64,
          serialize_u8 u8, serialize_u16 u16, serialize_u32 u32, serialize_u64 u64);
    fn serialize_f32(self, v: f32) -> Result<(), FrameError> {
        self.leaf(Leaf::F64(v.into()))
    }
    fn serialize_f64(self, v: f64) -> Result<(), FrameError> {
        self.leaf(Leaf::F64(v))
    }
    fn serialize_char(self, v: char) -> Result<(), FrameError> {
        self.leaf(Leaf::Text(v.to_string()))
    }
    fn serialize_str(self, v: &str) -> Result<(), FrameError> {
        if self.raw {
            // a pre-quoted cell: `"text"`, `""` = none
            let text = v.strip_prefix('"').and_then(|s| s.strip_suffix('"')).unwrap_or(v);
            let leaf = if text.is_empty() { Leaf::Missing } else { Leaf::Text(text.to_string()) };
            return Ser { optional: true, ..self }.leaf(leaf);
        }
        self.leaf(Leaf::Text(v.to_string()))
    }
    fn serialize_bytes(self, _: &[u8]) -> Result<(), FrameError> {
        Err(FrameError(format!("`{}`: bytes are not a column", self.t.path)))
    }
    fn serialize_none(self) -> Result<(), FrameError> {
        Ser { optional: true, ..self }.leaf(Leaf::Missing)
    }
    fn serialize_some<T: Serialize + ?Sized>(self, v: &T) -> Result<(), FrameError> {
        v.serialize(Ser { optional: true, ..self })
    }
    fn serialize_unit(self) -> Result<(), FrameError> {
        self.leaf(Leaf::Missing)
    }
    fn serialize_unit_struct(self, _: &'static str) -> Result<(), FrameError> {
        self.leaf(Leaf::Missing)
    }
    fn serialize_unit_variant(self, _: &'static str, _: u32, variant: &'static str) -> Result<(), FrameError> {
        self.leaf(Leaf::Text(variant.to_string()))
    }
    fn serialize_newtype_struct<T: Serialize + ?Sized>(self, name: &'static str, v: &T) -> Result<(), FrameError> {
        v.serialize(Ser { raw: name == RAW_CELL, ..self })
    }
    fn serialize_newtype_variant<T: Serialize + ?Sized>(
        self,
        _: &'static str,
        _: u32,
        variant: &'static str,
        _: &T,
    ) -> Result<(), FrameError> {
        Err(FrameError(format!("`{}`: the enum variant `{variant}` has data", self.t.path)))
    }
    fn serialize_seq(self, _: Option<usize>) -> Result<Fields<'a>, FrameError> {
        Ok(self.fields())
    }
    fn serialize_tuple(self, _: usize) -> Result<Fields<'a>, FrameError> {
        Ok(self.fields())
    }
    fn serialize_tuple_struct(self, _: &'static str, _: usize) -> Result<Fields<'a>, FrameError> {
        Ok(self.fields())
    }
    fn serialize_tuple_variant(
        self,
        _: &'static str,
        _: u32,
        v: &'static str,
        _: usize,
    ) -> Result<Self::SerializeTupleVariant, FrameError> {
        Err(FrameError(format!("`{}`: the enum variant `{v}` has data", self.t.path)))
    }
    fn serialize_map(self, _: Option<usize>) -> Result<Fields<'a>, FrameError> {
        Ok(self.fields())
    }
    fn serialize_struct(self, _: &'static str, _: usize) -> Result<Fields<'a>, FrameError> {
        Ok(self.fields())
    }
    fn serialize_struct_variant(
        self,
        _: &'static str,
        _: u32,
        v: &'static str,
        _: usize,
    ) -> Result<Self::SerializeStructVariant, FrameError> {
        Err(FrameError(format!("`{}`: the enum variant `{v}` has data", self.t.path)))
    }
}

/// serde's three kinds of sequence (`[T]`, tuples, tuple structs): elements `key_0`, `key_1`, …
macro_rules! elements {
    ($($trait:ident $method:ident),*) => {$(
        impl ser::$trait for Fields<'_> {
            type Ok = ();
            type Error = FrameError;
            fn $method<T: Serialize + ?Sized>(&mut self, v: &T) -> Result<(), FrameError> {
                self.element(v)
            }
            fn end(self) -> Result<(), FrameError> {
                Ok(())
            }
        }
    )*};
}
elements!(SerializeSeq serialize_element, SerializeTuple serialize_element, SerializeTupleStruct serialize_field);

impl ser::SerializeStruct for Fields<'_> {
    type Ok = ();
    type Error = FrameError;
    fn serialize_field<T: Serialize + ?Sized>(&mut self, name: &'static str, v: &T) -> Result<(), FrameError> {
        self.field(name, v)
    }
    fn end(self) -> Result<(), FrameError> {
        Ok(())
    }
}

impl ser::SerializeMap for Fields<'_> {
    type Ok = ();
    type Error = FrameError;
    fn serialize_key<T: Serialize + ?Sized>(&mut self, _: &T) -> Result<(), FrameError> {
        Err(FrameError("a map's key and value apart".into()))
    }
    fn serialize_value<T: Serialize + ?Sized>(&mut self, _: &T) -> Result<(), FrameError> {
        Err(FrameError("a map's key and value apart".into()))
    }
    fn serialize_entry<K: Serialize + ?Sized, V: Serialize + ?Sized>(
        &mut self,
        k: &K,
        v: &V,
    ) -> Result<(), FrameError> {
        // the key appended to the path in place (no allocation per field)
        self.t.path.truncate(self.base);
        if self.base > 0 {
            self.t.path.push('.');
        }
        k.serialize(KeyText(&mut self.t.path))?;
        self.value(v)
    }
    fn end(self) -> Result<(), FrameError> {
        Ok(())
    }
}

/// A map key, appended to a key as text.
struct KeyText<'a>(&'a mut String);

impl ser::Serializer for KeyText<'_> {
    type Ok = ();
    type Error = FrameError;
    type SerializeSeq = Impossible<(), FrameError>;
    type SerializeTuple = Impossible<(), FrameError>;
    type SerializeTupleStruct = Impossible<(), FrameError>;
    type SerializeTupleVariant = Impossible<(), FrameError>;
    type SerializeMap = Impossible<(), FrameError>;
    type SerializeStruct = Impossible<(), FrameError>;
    type SerializeStructVariant = Impossible<(), FrameError>;
    fn serialize_str(self, v: &str) -> Result<(), FrameError> {
        self.0.push_str(v);
        Ok(())
    }
    fn serialize_bool(self, _: bool) -> Result<(), FrameError> {
        Err(ser::Error::custom("a map key must be text"))
    }
    fn serialize_i8(self, _: i8) -> Result<(), FrameError> {
        Err(ser::Error::custom("a map key must be text"))
    }
    fn serialize_i16(self, _: i16) -> Result<(), FrameError> {
        Err(ser::Error::custom("a map key must be text"))
    }
    fn serialize_i32(self, _: i32) -> Result<(), FrameError> {
        Err(ser::Error::custom("a map key must be text"))
    }
    fn serialize_i64(self, _: i64) -> Result<(), FrameError> {
        Err(ser::Error::custom("a map key must be text"))
    }
    fn serialize_u8(self, _: u8) -> Result<(), FrameError> {
        Err(ser::Error::custom("a map key must be text"))
    }
    fn serialize_u16(self, _: u16) -> Result<(), FrameError> {
        Err(ser::Error::custom("a map key must be text"))
    }
    fn serialize_u32(self, _: u32) -> Result<(), FrameError> {
        Err(ser::Error::custom("a map key must be text"))
    }
    fn serialize_u64(self, _: u64) -> Result<(), FrameError> {
        Err(ser::Error::custom("a map key must be text"))
    }
    fn serialize_f32(self, _: f32) -> Result<(), FrameError> {
        Err(ser::Error::custom("a map key must be text"))
    }
    fn serialize_f64(self, _: f64) -> Result<(), FrameError> {
        Err(ser::Error::custom("a map key must be text"))
    }
    fn serialize_char(self, v: char) -> Result<(), FrameError> {
        self.0.push(v);
        Ok(())
    }
    fn serialize_bytes(self, _: &[u8]) -> Result<(), FrameError> {
        Err(ser::Error::custom("a map key must be text"))
    }
    fn serialize_none(self) -> Result<(), FrameError> {
        Err(ser::Error::custom("a map key must be text"))
    }
    fn serialize_some<T: Serialize + ?Sized>(self, _: &T) -> Result<(), FrameError> {
        Err(ser::Error::custom("a map key must be text"))
    }
    fn serialize_unit(self) -> Result<(), FrameError> {
        Err(ser::Error::custom("a map key must be text"))
    }
    fn serialize_unit_struct(self, _: &'static str) -> Result<(), FrameError> {
        Err(ser::Error::custom("a map key must be text"))
    }
    fn serialize_unit_variant(self, _: &'static str, _: u32, v: &'static str) -> Result<(), FrameError> {
        self.0.push_str(v);
        Ok(())
    }
    fn serialize_newtype_struct<T: Serialize + ?Sized>(self, _: &'static str, v: &T) -> Result<(), FrameError> {
        v.serialize(self)
    }
    fn serialize_newtype_variant<T: Serialize + ?Sized>(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        _: &T,
    ) -> Result<(), FrameError> {
        Err(ser::Error::custom("a map key must be text"))
    }
    fn serialize_seq(self, _: Option<usize>) -> Result<Self::SerializeSeq, FrameError> {
        Err(ser::Error::custom("a map key must be text"))
    }
    fn serialize_tuple(self, _: usize) -> Result<Self::SerializeTuple, FrameError> {
        Err(ser::Error::custom("a map key must be text"))
    }
    fn serialize_tuple_struct(self, _: &'static str, _: usize) -> Result<Self::SerializeTupleStruct, FrameError> {
        Err(ser::Error::custom("a map key must be text"))
    }
    fn serialize_tuple_variant(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        _: usize,
    ) -> Result<Self::SerializeTupleVariant, FrameError> {
        Err(ser::Error::custom("a map key must be text"))
    }
    fn serialize_map(self, _: Option<usize>) -> Result<Self::SerializeMap, FrameError> {
        Err(ser::Error::custom("a map key must be text"))
    }
    fn serialize_struct(self, _: &'static str, _: usize) -> Result<Self::SerializeStruct, FrameError> {
        Err(ser::Error::custom("a map key must be text"))
    }
    fn serialize_struct_variant(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        _: usize,
    ) -> Result<Self::SerializeStructVariant, FrameError> {
        Err(ser::Error::custom("a map key must be text"))
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
