//! A flat record as named leaf values, by serde: one leaf per field of a struct (fields of
//! flattened structs by their own names, of nested ones as `outer.inner`, arrays as
//! `name_0`, `name_1`, …, `None` missing), walked once ([`walk_row`]) into a [`RowSink`]:
//! CSV cells here (the run's tables, verify.csv and sweep.csv are written from their typed
//! rows, so a row's type is the one list of its columns), DataFrame columns in the Python
//! package (crates/gripopt-py/src/frame.rs).

use serde::ser::{self, Impossible, Serialize};
use std::fmt::{self, Display};

/// How numbers are written.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Floats {
    /// Rust's `{}` (shortest round-trip digits, never an exponent; `NaN`, `inf`).
    Display,
    /// JSON's (shortest round-trip digits, exponent when shorter; non-finite: empty).
    Json,
}

/// A cell written as it is (already quoted), never quoted again.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct RawCell(pub String);

const RAW: &str = "gripopt::RawCell";

impl Serialize for RawCell {
    fn serialize<S: ser::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_newtype_struct(RAW, &self.0)
    }
}

/// A value that cannot be a cell (a map key that is not text, an enum with data, bytes).
#[derive(Debug)]
pub struct CellError(String);

impl Display for CellError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}
impl std::error::Error for CellError {}
impl ser::Error for CellError {
    fn custom<T: Display>(msg: T) -> Self {
        CellError(msg.to_string())
    }
}

/// The (column, cell) pairs of `row`, in field order; text with a comma, quote or line
/// break is quoted CSV-style.
pub(crate) fn cells<T: Serialize + ?Sized>(row: &T, floats: Floats) -> Vec<(String, String)> {
    let mut sink = CsvCells { out: Vec::new(), floats };
    // a row of plain fields cannot fail; a type that does is a bug in its Serialize
    walk_row(row, &mut sink, &mut String::new()).expect("a row of plain fields serialises to cells");
    sink.out
}

/// One line of CSV: the cells of `row` joined by commas, with a line break.
pub(crate) fn line<T: Serialize + ?Sized>(row: &T, floats: Floats) -> String {
    let mut s = cells(row, floats).into_iter().map(|(_, c)| c).collect::<Vec<_>>().join(",");
    s.push('\n');
    s
}

/// The column names of a row type (from a value of it).
pub(crate) fn header<T: Serialize + ?Sized>(row: &T) -> Vec<String> {
    cells(row, Floats::Display).into_iter().map(|(k, _)| k).collect()
}

/// A text cell, quoted CSV-style (RFC 4180) where it holds a comma, a quote or a line break.
pub(crate) fn quoted(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// The CSV sink: each leaf as its cell's text.
struct CsvCells {
    out: Vec<(String, String)>,
    floats: Floats,
}

impl RowSink for CsvCells {
    fn leaf(&mut self, key: &str, value: Leaf<'_>, _optional: bool) -> Result<(), CellError> {
        let text = match value {
            Leaf::Bool(v) => v.to_string(),
            Leaf::I64(v) => v.to_string(),
            Leaf::U64(v) => v.to_string(),
            Leaf::F64(v) => match self.floats {
                Floats::Display => format!("{v}"),
                // serde_json writes a finite f64 with ryu's shortest digits
                Floats::Json if v.is_finite() => serde_json::to_string(&v).unwrap_or_default(),
                Floats::Json => String::new(),
            },
            Leaf::Char(c) => quoted(c.encode_utf8(&mut [0; 4])),
            Leaf::Str(s) | Leaf::Variant(s) => quoted(s),
            Leaf::Raw(s) => s.to_string(),
            Leaf::Missing => String::new(),
        };
        self.out.push((key.to_string(), text));
        Ok(())
    }
}

/// A leaf value of a row.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Leaf<'v> {
    /// A boolean.
    Bool(bool),
    /// A signed integer.
    I64(i64),
    /// An unsigned integer.
    U64(u64),
    /// A float (an `f32` widened).
    F64(f64),
    /// A character.
    Char(char),
    /// Text.
    Str(&'v str),
    /// A pre-quoted CSV cell (a `RawCell`): `"text"`, `""` = none.
    Raw(&'v str),
    /// A unit enum variant's name.
    Variant(&'static str),
    /// `None` or a unit.
    Missing,
}

/// Where [`walk_row`] puts a row's leaves.
pub trait RowSink {
    /// The leaf at column `key`; `optional`: inside an `Option` (or `None` itself).
    fn leaf(&mut self, key: &str, value: Leaf<'_>, optional: bool) -> Result<(), CellError>;
}

/// Walk `row` (a struct or map) into `sink`, leaf by leaf in field order; `key` is a buffer
/// for the column names (reused between rows: no allocation per field).
pub fn walk_row<T: Serialize + ?Sized, S: RowSink>(row: &T, sink: &mut S, key: &mut String) -> Result<(), CellError> {
    key.clear();
    row.serialize(Walk { sink, key, optional: false, raw: false })
}

/// The serializer of one value at `key`.
struct Walk<'a, S> {
    sink: &'a mut S,
    key: &'a mut String,
    /// Inside an `Option`.
    optional: bool,
    /// A pre-quoted CSV cell.
    raw: bool,
}

impl<'a, S: RowSink> Walk<'a, S> {
    fn leaf(self, v: Leaf<'_>) -> Result<(), CellError> {
        self.sink.leaf(self.key, v, self.optional)
    }
    fn fields(self) -> Fields<'a, S> {
        let base = self.key.len();
        Fields { sink: self.sink, key: self.key, base, n: 0, optional: self.optional }
    }
}

/// A struct, map or sequence: each field or element at its own key.
struct Fields<'a, S> {
    sink: &'a mut S,
    key: &'a mut String,
    /// The key's length before this value's fields were appended.
    base: usize,
    /// Elements so far (sequences).
    n: usize,
    optional: bool,
}

impl<S: RowSink> Fields<'_, S> {
    /// The key back to this value's, then `.` if it is not the row's own.
    fn restart(&mut self) {
        self.key.truncate(self.base);
        if self.base > 0 {
            self.key.push('.');
        }
    }
    /// The value of the field whose name is already in the key.
    fn value<T: Serialize + ?Sized>(&mut self, v: &T) -> Result<(), CellError> {
        v.serialize(Walk { sink: &mut *self.sink, key: &mut *self.key, optional: self.optional, raw: false })?;
        self.key.truncate(self.base);
        Ok(())
    }
    fn element<T: Serialize + ?Sized>(&mut self, v: &T) -> Result<(), CellError> {
        use std::fmt::Write as _;
        self.key.truncate(self.base);
        let _ = write!(self.key, "_{}", self.n);
        self.n += 1;
        self.value(v)
    }
}

fn with_data(key: &str, variant: &str) -> CellError {
    CellError(format!("`{key}`: the enum variant `{variant}` has data"))
}

impl<'a, S: RowSink> ser::Serializer for Walk<'a, S> {
    type Ok = ();
    type Error = CellError;
    type SerializeSeq = Fields<'a, S>;
    type SerializeTuple = Fields<'a, S>;
    type SerializeTupleStruct = Fields<'a, S>;
    type SerializeTupleVariant = Impossible<(), CellError>;
    type SerializeMap = Fields<'a, S>;
    type SerializeStruct = Fields<'a, S>;
    type SerializeStructVariant = Impossible<(), CellError>;

    fn serialize_bool(self, v: bool) -> Result<(), CellError> {
        self.leaf(Leaf::Bool(v))
    }
    fn serialize_i8(self, v: i8) -> Result<(), CellError> {
        self.leaf(Leaf::I64(v.into()))
    }
    fn serialize_i16(self, v: i16) -> Result<(), CellError> {
        self.leaf(Leaf::I64(v.into()))
    }
    fn serialize_i32(self, v: i32) -> Result<(), CellError> {
        self.leaf(Leaf::I64(v.into()))
    }
    fn serialize_i64(self, v: i64) -> Result<(), CellError> {
        self.leaf(Leaf::I64(v))
    }
    fn serialize_u8(self, v: u8) -> Result<(), CellError> {
        self.leaf(Leaf::U64(v.into()))
    }
    fn serialize_u16(self, v: u16) -> Result<(), CellError> {
        self.leaf(Leaf::U64(v.into()))
    }
    fn serialize_u32(self, v: u32) -> Result<(), CellError> {
        self.leaf(Leaf::U64(v.into()))
    }
    fn serialize_u64(self, v: u64) -> Result<(), CellError> {
        self.leaf(Leaf::U64(v))
    }
    fn serialize_f32(self, v: f32) -> Result<(), CellError> {
        self.leaf(Leaf::F64(v.into()))
    }
    fn serialize_f64(self, v: f64) -> Result<(), CellError> {
        self.leaf(Leaf::F64(v))
    }
    fn serialize_char(self, v: char) -> Result<(), CellError> {
        self.leaf(Leaf::Char(v))
    }
    fn serialize_str(self, v: &str) -> Result<(), CellError> {
        let raw = self.raw;
        self.leaf(if raw { Leaf::Raw(v) } else { Leaf::Str(v) })
    }
    fn serialize_bytes(self, _: &[u8]) -> Result<(), CellError> {
        Err(CellError(format!("`{}`: bytes are not a cell", self.key)))
    }
    fn serialize_none(self) -> Result<(), CellError> {
        Walk { optional: true, ..self }.leaf(Leaf::Missing)
    }
    fn serialize_some<T: Serialize + ?Sized>(self, v: &T) -> Result<(), CellError> {
        v.serialize(Walk { optional: true, ..self })
    }
    fn serialize_unit(self) -> Result<(), CellError> {
        self.leaf(Leaf::Missing)
    }
    fn serialize_unit_struct(self, _: &'static str) -> Result<(), CellError> {
        self.leaf(Leaf::Missing)
    }
    fn serialize_unit_variant(self, _: &'static str, _: u32, variant: &'static str) -> Result<(), CellError> {
        self.leaf(Leaf::Variant(variant))
    }
    fn serialize_newtype_struct<T: Serialize + ?Sized>(self, name: &'static str, v: &T) -> Result<(), CellError> {
        v.serialize(Walk { raw: name == RAW, ..self })
    }
    fn serialize_newtype_variant<T: Serialize + ?Sized>(
        self,
        _: &'static str,
        _: u32,
        variant: &'static str,
        _: &T,
    ) -> Result<(), CellError> {
        Err(with_data(self.key, variant))
    }
    fn serialize_seq(self, _: Option<usize>) -> Result<Fields<'a, S>, CellError> {
        Ok(self.fields())
    }
    fn serialize_tuple(self, _: usize) -> Result<Fields<'a, S>, CellError> {
        Ok(self.fields())
    }
    fn serialize_tuple_struct(self, _: &'static str, _: usize) -> Result<Fields<'a, S>, CellError> {
        Ok(self.fields())
    }
    fn serialize_tuple_variant(
        self,
        _: &'static str,
        _: u32,
        variant: &'static str,
        _: usize,
    ) -> Result<Self::SerializeTupleVariant, CellError> {
        Err(with_data(self.key, variant))
    }
    fn serialize_map(self, _: Option<usize>) -> Result<Fields<'a, S>, CellError> {
        Ok(self.fields())
    }
    fn serialize_struct(self, _: &'static str, _: usize) -> Result<Fields<'a, S>, CellError> {
        Ok(self.fields())
    }
    fn serialize_struct_variant(
        self,
        _: &'static str,
        _: u32,
        variant: &'static str,
        _: usize,
    ) -> Result<Self::SerializeStructVariant, CellError> {
        Err(with_data(self.key, variant))
    }
}

/// serde's three kinds of sequence (`[T]`, tuples, tuple structs): elements `key_0`, `key_1`, …
macro_rules! elements {
    ($($trait:ident $method:ident),*) => {$(
        impl<S: RowSink> ser::$trait for Fields<'_, S> {
            type Ok = ();
            type Error = CellError;
            fn $method<T: Serialize + ?Sized>(&mut self, v: &T) -> Result<(), CellError> {
                self.element(v)
            }
            fn end(self) -> Result<(), CellError> {
                Ok(())
            }
        }
    )*};
}
elements!(SerializeSeq serialize_element, SerializeTuple serialize_element, SerializeTupleStruct serialize_field);

impl<S: RowSink> ser::SerializeStruct for Fields<'_, S> {
    type Ok = ();
    type Error = CellError;
    fn serialize_field<T: Serialize + ?Sized>(&mut self, name: &'static str, v: &T) -> Result<(), CellError> {
        self.restart();
        self.key.push_str(name);
        self.value(v)
    }
    fn end(self) -> Result<(), CellError> {
        Ok(())
    }
}

impl<S: RowSink> ser::SerializeMap for Fields<'_, S> {
    type Ok = ();
    type Error = CellError;
    fn serialize_key<T: Serialize + ?Sized>(&mut self, _: &T) -> Result<(), CellError> {
        Err(CellError("a map's key and value apart".into()))
    }
    fn serialize_value<T: Serialize + ?Sized>(&mut self, _: &T) -> Result<(), CellError> {
        Err(CellError("a map's key and value apart".into()))
    }
    fn serialize_entry<K: Serialize + ?Sized, V: Serialize + ?Sized>(&mut self, k: &K, v: &V) -> Result<(), CellError> {
        // the key appended to the column name in place
        self.restart();
        k.serialize(KeyText(&mut *self.key))?;
        self.value(v)
    }
    fn end(self) -> Result<(), CellError> {
        Ok(())
    }
}

/// A map key, appended to a key as text (a string, a number, a unit variant).
struct KeyText<'a>(&'a mut String);

impl KeyText<'_> {
    fn text(self, v: impl Display) -> Result<(), CellError> {
        use std::fmt::Write as _;
        let _ = write!(self.0, "{v}");
        Ok(())
    }
}

impl ser::Serializer for KeyText<'_> {
    type Ok = ();
    type Error = CellError;
    type SerializeSeq = Impossible<(), CellError>;
    type SerializeTuple = Impossible<(), CellError>;
    type SerializeTupleStruct = Impossible<(), CellError>;
    type SerializeTupleVariant = Impossible<(), CellError>;
    type SerializeMap = Impossible<(), CellError>;
    type SerializeStruct = Impossible<(), CellError>;
    type SerializeStructVariant = Impossible<(), CellError>;
    fn serialize_str(self, v: &str) -> Result<(), CellError> {
        self.0.push_str(v);
        Ok(())
    }
    fn serialize_bool(self, v: bool) -> Result<(), CellError> {
        self.text(v)
    }
    fn serialize_i8(self, v: i8) -> Result<(), CellError> {
        self.text(v)
    }
    fn serialize_i16(self, v: i16) -> Result<(), CellError> {
        self.text(v)
    }
    fn serialize_i32(self, v: i32) -> Result<(), CellError> {
        self.text(v)
    }
    fn serialize_i64(self, v: i64) -> Result<(), CellError> {
        self.text(v)
    }
    fn serialize_u8(self, v: u8) -> Result<(), CellError> {
        self.text(v)
    }
    fn serialize_u16(self, v: u16) -> Result<(), CellError> {
        self.text(v)
    }
    fn serialize_u32(self, v: u32) -> Result<(), CellError> {
        self.text(v)
    }
    fn serialize_u64(self, v: u64) -> Result<(), CellError> {
        self.text(v)
    }
    fn serialize_f32(self, _: f32) -> Result<(), CellError> {
        Err(ser::Error::custom("a map key must be text"))
    }
    fn serialize_f64(self, _: f64) -> Result<(), CellError> {
        Err(ser::Error::custom("a map key must be text"))
    }
    fn serialize_char(self, v: char) -> Result<(), CellError> {
        self.0.push(v);
        Ok(())
    }
    fn serialize_bytes(self, _: &[u8]) -> Result<(), CellError> {
        Err(ser::Error::custom("a map key must be text"))
    }
    fn serialize_none(self) -> Result<(), CellError> {
        Err(ser::Error::custom("a map key must be text"))
    }
    fn serialize_some<T: Serialize + ?Sized>(self, _: &T) -> Result<(), CellError> {
        Err(ser::Error::custom("a map key must be text"))
    }
    fn serialize_unit(self) -> Result<(), CellError> {
        Err(ser::Error::custom("a map key must be text"))
    }
    fn serialize_unit_struct(self, _: &'static str) -> Result<(), CellError> {
        Err(ser::Error::custom("a map key must be text"))
    }
    fn serialize_unit_variant(self, _: &'static str, _: u32, v: &'static str) -> Result<(), CellError> {
        self.0.push_str(v);
        Ok(())
    }
    fn serialize_newtype_struct<T: Serialize + ?Sized>(self, _: &'static str, v: &T) -> Result<(), CellError> {
        v.serialize(self)
    }
    fn serialize_newtype_variant<T: Serialize + ?Sized>(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        _: &T,
    ) -> Result<(), CellError> {
        Err(ser::Error::custom("a map key must be text"))
    }
    fn serialize_seq(self, _: Option<usize>) -> Result<Self::SerializeSeq, CellError> {
        Err(ser::Error::custom("a map key must be text"))
    }
    fn serialize_tuple(self, _: usize) -> Result<Self::SerializeTuple, CellError> {
        Err(ser::Error::custom("a map key must be text"))
    }
    fn serialize_tuple_struct(self, _: &'static str, _: usize) -> Result<Self::SerializeTupleStruct, CellError> {
        Err(ser::Error::custom("a map key must be text"))
    }
    fn serialize_tuple_variant(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        _: usize,
    ) -> Result<Self::SerializeTupleVariant, CellError> {
        Err(ser::Error::custom("a map key must be text"))
    }
    fn serialize_map(self, _: Option<usize>) -> Result<Self::SerializeMap, CellError> {
        Err(ser::Error::custom("a map key must be text"))
    }
    fn serialize_struct(self, _: &'static str, _: usize) -> Result<Self::SerializeStruct, CellError> {
        Err(ser::Error::custom("a map key must be text"))
    }
    fn serialize_struct_variant(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        _: usize,
    ) -> Result<Self::SerializeStructVariant, CellError> {
        Err(ser::Error::custom("a map key must be text"))
    }
}
