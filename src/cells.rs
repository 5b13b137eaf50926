//! A flat record as CSV cells, by serde: one cell per field of a struct (fields of
//! flattened structs by their own names, of nested ones as `outer.inner`, arrays as
//! `name_0`, `name_1`, …, `None` as an empty cell). The run's tables, verify.csv and sweep.csv are written from their
//! typed rows through it, so a row's type is the one list of its columns.

use serde::ser::{self, Impossible, Serialize, SerializeMap, SerializeSeq, SerializeStruct, SerializeTuple};
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

/// A value that cannot be a cell (a map key that is not a string, an enum with data).
#[derive(Debug)]
pub(crate) struct CellError(String);

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
    let mut out = Vec::new();
    // a row of plain fields cannot fail; a type that does is a bug in its Serialize
    // a row is a struct or map: a cell without a name, whose fields are the cells
    let top = Cell { key: String::new(), out: &mut out, floats, raw: false };
    row.serialize(top).expect("a row of plain fields serialises to cells");
    out
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

fn quoted(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// The serializer of a struct or map: each field becomes cells (named `prefix.field` in a
/// nested struct).
struct Fields<'a> {
    out: &'a mut Vec<(String, String)>,
    floats: Floats,
    prefix: Option<String>,
}

impl Fields<'_> {
    fn name(&self, key: &str) -> String {
        match &self.prefix {
            Some(p) => format!("{p}.{key}"),
            None => key.to_string(),
        }
    }
}

/// The serializer of one field's value.
struct Cell<'a> {
    key: String,
    out: &'a mut Vec<(String, String)>,
    floats: Floats,
    raw: bool,
}

impl<'a> Cell<'a> {
    /// The fields of a struct or map in this cell: `key.field` (the row's own: `field`).
    fn fields(self) -> Fields<'a> {
        let prefix = (!self.key.is_empty()).then_some(self.key);
        Fields { out: self.out, floats: self.floats, prefix }
    }
    fn put(self, text: String) -> Result<(), CellError> {
        let text = if self.raw { text } else { quoted(&text) };
        self.out.push((self.key, text));
        Ok(())
    }
    fn float(self, v: f64) -> Result<(), CellError> {
        let text = match self.floats {
            Floats::Display => format!("{v}"),
            // serde_json writes a finite f64 with ryu's shortest digits
            Floats::Json if v.is_finite() => serde_json::to_string(&v).unwrap_or_default(),
            Floats::Json => String::new(),
        };
        self.put(text)
    }
}

macro_rules! display_cells {
    ($($f:ident: $t:ty),*) => {
        $(fn $f(self, v: $t) -> Result<(), CellError> { self.put(v.to_string()) })*
    };
}

impl<'a> ser::Serializer for Cell<'a> {
    type Ok = ();
    type Error = CellError;
    type SerializeSeq = Items<'a>;
    type SerializeTuple = Items<'a>;
    type SerializeTupleStruct = Impossible<(), CellError>;
    type SerializeTupleVariant = Impossible<(), CellError>;
    type SerializeMap = Fields<'a>;
    type SerializeStruct = Fields<'a>;
    type SerializeStructVariant = Impossible<(), CellError>;

    display_cells!(serialize_bool: bool, serialize_i8: i8, serialize_i16: i16, serialize_i32: i32, serialize_i64: i64,
        serialize_u8: u8, serialize_u16: u16, serialize_u32: u32, serialize_u64: u64, serialize_char: char,
        serialize_str: &str);
    fn serialize_f32(self, v: f32) -> Result<(), CellError> {
        self.float(v as f64)
    }
    fn serialize_f64(self, v: f64) -> Result<(), CellError> {
        self.float(v)
    }
    fn serialize_bytes(self, _: &[u8]) -> Result<(), CellError> {
        Err(CellError("bytes are not a cell".into()))
    }
    fn serialize_none(self) -> Result<(), CellError> {
        self.put(String::new())
    }
    fn serialize_some<T: Serialize + ?Sized>(self, v: &T) -> Result<(), CellError> {
        v.serialize(self)
    }
    fn serialize_unit(self) -> Result<(), CellError> {
        self.put(String::new())
    }
    fn serialize_unit_struct(self, _: &'static str) -> Result<(), CellError> {
        self.put(String::new())
    }
    fn serialize_unit_variant(self, _: &'static str, _: u32, variant: &'static str) -> Result<(), CellError> {
        self.put(variant.to_string())
    }
    fn serialize_newtype_struct<T: Serialize + ?Sized>(self, name: &'static str, v: &T) -> Result<(), CellError> {
        v.serialize(Cell { raw: name == RAW, ..self })
    }
    fn serialize_newtype_variant<T: Serialize + ?Sized>(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        _: &T,
    ) -> Result<(), CellError> {
        Err(CellError("an enum with data is not a cell".into()))
    }
    fn serialize_seq(self, _: Option<usize>) -> Result<Items<'a>, CellError> {
        Ok(Items { key: self.key, out: self.out, floats: self.floats, next: 0 })
    }
    fn serialize_tuple(self, n: usize) -> Result<Items<'a>, CellError> {
        self.serialize_seq(Some(n))
    }
    fn serialize_tuple_struct(self, _: &'static str, _: usize) -> Result<Self::SerializeTupleStruct, CellError> {
        Err(CellError("a tuple struct is not a cell".into()))
    }
    fn serialize_tuple_variant(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        _: usize,
    ) -> Result<Self::SerializeTupleVariant, CellError> {
        Err(CellError("an enum with data is not a cell".into()))
    }
    fn serialize_map(self, _: Option<usize>) -> Result<Fields<'a>, CellError> {
        Ok(self.fields())
    }
    fn serialize_struct(self, _: &'static str, _: usize) -> Result<Fields<'a>, CellError> {
        Ok(self.fields())
    }
    fn serialize_struct_variant(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        _: usize,
    ) -> Result<Self::SerializeStructVariant, CellError> {
        Err(CellError("an enum with data is not a cell".into()))
    }
}

/// An array field: `key_0`, `key_1`, …
struct Items<'a> {
    key: String,
    out: &'a mut Vec<(String, String)>,
    floats: Floats,
    next: usize,
}

impl SerializeSeq for Items<'_> {
    type Ok = ();
    type Error = CellError;
    fn serialize_element<T: Serialize + ?Sized>(&mut self, v: &T) -> Result<(), CellError> {
        let key = format!("{}_{}", self.key, self.next);
        self.next += 1;
        v.serialize(Cell { key, out: self.out, floats: self.floats, raw: false })
    }
    fn end(self) -> Result<(), CellError> {
        Ok(())
    }
}

impl SerializeTuple for Items<'_> {
    type Ok = ();
    type Error = CellError;
    fn serialize_element<T: Serialize + ?Sized>(&mut self, v: &T) -> Result<(), CellError> {
        SerializeSeq::serialize_element(self, v)
    }
    fn end(self) -> Result<(), CellError> {
        Ok(())
    }
}

impl SerializeStruct for Fields<'_> {
    type Ok = ();
    type Error = CellError;
    fn serialize_field<T: Serialize + ?Sized>(&mut self, key: &'static str, v: &T) -> Result<(), CellError> {
        let key = self.name(key);
        v.serialize(Cell { key, out: self.out, floats: self.floats, raw: false })
    }
    fn end(self) -> Result<(), CellError> {
        Ok(())
    }
}

impl SerializeMap for Fields<'_> {
    type Ok = ();
    type Error = CellError;
    fn serialize_key<T: Serialize + ?Sized>(&mut self, _: &T) -> Result<(), CellError> {
        Err(CellError("use serialize_entry".into()))
    }
    fn serialize_value<T: Serialize + ?Sized>(&mut self, _: &T) -> Result<(), CellError> {
        Err(CellError("use serialize_entry".into()))
    }
    fn serialize_entry<K: Serialize + ?Sized, V: Serialize + ?Sized>(&mut self, k: &K, v: &V) -> Result<(), CellError> {
        let mut key = Vec::new();
        k.serialize(Cell { key: String::new(), out: &mut key, floats: self.floats, raw: true })?;
        let key = key.pop().map(|(_, k)| k).ok_or_else(|| CellError("a map key that is not a string".into()))?;
        let key = self.name(&key);
        v.serialize(Cell { key, out: self.out, floats: self.floats, raw: false })
    }
    fn end(self) -> Result<(), CellError> {
        Ok(())
    }
}
