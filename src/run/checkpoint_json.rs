//! Canonical JSON written streaming: the bytes of `serde_json::to_vec(&serde_json::to_value(v))`
//! (every object's keys sorted, as `serde_json::Value`'s maps sort them) without building the
//! `Value` tree, which for a checkpoint of a large population cost several times the file's
//! size in tree nodes (issue 23 item 3).
//!
//! Scalars and arrays are written as they come. An object's fields are buffered, each as its
//! bytes, and written sorted when the object ends, so the memory is one object's bytes, not
//! the document's; a struct named in [`Canonical::sorted`] declares its fields in sorted
//! order and is written straight through instead (a field out of order is an error, never a
//! wrong file): that is how a checkpoint's large objects (the state with its population, the
//! archive) never sit in a buffer. The checkpoint's own checksum field is inserted at its
//! sorted place in the top-level object ([`Canonical::with_field`]).

use serde::ser::{self, Serialize, SerializeMap as _, Serializer as _};
use serde_json::Error;
use std::io::Write;

type Result<T> = std::result::Result<T, Error>;

/// A serializer writing canonical JSON to `W`.
pub struct Canonical<'s, W> {
    out: W,
    /// Structs whose fields are declared in sorted order (written through).
    sorted: &'s [&'static str],
    /// A field added to the top-level object at its sorted place (key, JSON string value).
    extra: Option<(&'static str, &'s str)>,
}

impl<'s, W: Write> Canonical<'s, W> {
    /// Canonical JSON into `out`; the structs named in `sorted` declare their fields in
    /// sorted order.
    pub fn new(out: W, sorted: &'s [&'static str]) -> Self {
        Canonical { out, sorted, extra: None }
    }

    /// Add the string field `key: value` to the top-level object, at its sorted place.
    pub fn with_field(mut self, key: &'static str, value: &'s str) -> Self {
        self.extra = Some((key, value));
        self
    }

    /// The writer.
    pub fn into_inner(self) -> W {
        self.out
    }

    fn json(&mut self) -> serde_json::Serializer<&mut W> {
        serde_json::Serializer::new(&mut self.out)
    }

    fn raw(&mut self, b: &[u8]) -> Result<()> {
        self.out.write_all(b).map_err(Error::io)
    }

    /// A value's canonical bytes (an object's field, buffered until the object ends).
    fn bytes_of<T: ?Sized + Serialize>(&self, v: &T) -> Result<Vec<u8>> {
        let mut c = Canonical::new(Vec::new(), self.sorted);
        v.serialize(&mut c)?;
        Ok(c.out)
    }

    fn open(&mut self, sorted_struct: bool) -> Result<Object<'_, 's, W>> {
        // only the first object opened is the top-level one
        let extra = self.extra.take();
        self.raw(b"{")?;
        Ok(Object { c: self, through: sorted_struct, entries: vec![], last: None, first: true, extra, key: None })
    }

    /// `{"variant":` before a variant's content (closed by `}`).
    fn variant_head(&mut self, variant: &str) -> Result<()> {
        self.extra = None;
        self.raw(b"{")?;
        self.json().serialize_str(variant)?;
        self.raw(b":")
    }
}

/// The string a map key becomes in a `serde_json::Value` (strings, numbers, booleans, unit
/// variants; anything else is refused as `Value` refuses it).
fn key_string<T: ?Sized + Serialize>(key: &T) -> Result<String> {
    let mut m = serde_json::value::Serializer.serialize_map(Some(1))?;
    m.serialize_key(key)?;
    m.serialize_value(&())?;
    match m.end()? {
        serde_json::Value::Object(o) => Ok(o.into_iter().next().map(|(k, _)| k).unwrap_or_default()),
        _ => Err(ser::Error::custom("a map key did not become a string")),
    }
}

/// An array being written.
pub struct Array<'a, 's, W> {
    c: &'a mut Canonical<'s, W>,
    first: bool,
    /// Closing bytes (`]`, or `]}` for a tuple variant).
    close: &'static [u8],
}

impl<W: Write> Array<'_, '_, W> {
    fn element<T: ?Sized + Serialize>(&mut self, v: &T) -> Result<()> {
        if !self.first {
            self.c.raw(b",")?;
        }
        self.first = false;
        v.serialize(&mut *self.c)
    }
    fn close(self) -> Result<()> {
        self.c.raw(self.close)
    }
}

/// An object being written: buffered entries sorted at its end, or (a struct declared in
/// sorted order) written through.
pub struct Object<'a, 's, W> {
    c: &'a mut Canonical<'s, W>,
    through: bool,
    entries: Vec<(String, Vec<u8>)>,
    last: Option<&'static str>,
    first: bool,
    extra: Option<(&'static str, &'s str)>,
    /// A map's key waiting for its value.
    key: Option<String>,
}

impl<W: Write> Object<'_, '_, W> {
    fn write_entry(&mut self, key: &str, value: &[u8]) -> Result<()> {
        if !self.first {
            self.c.raw(b",")?;
        }
        self.first = false;
        self.c.json().serialize_str(key)?;
        self.c.raw(b":")?;
        self.c.raw(value)
    }

    fn write_extra_before(&mut self, key: Option<&str>) -> Result<()> {
        if let Some((k, v)) = self.extra.filter(|(k, _)| key.is_none_or(|key| *k < key)) {
            self.extra = None;
            let v = serde_json::to_vec(v)?;
            self.write_entry(k, &v)?;
        }
        Ok(())
    }

    fn field<T: ?Sized + Serialize>(&mut self, key: &'static str, v: &T) -> Result<()> {
        if !self.through {
            let bytes = self.c.bytes_of(v)?;
            self.entries.push((key.to_string(), bytes));
            return Ok(());
        }
        if self.last.is_some_and(|last| last >= key) {
            return Err(ser::Error::custom(format!(
                "field `{key}` after `{}`: a struct written through must declare its fields in sorted order",
                self.last.unwrap_or_default()
            )));
        }
        self.last = Some(key);
        self.write_extra_before(Some(key))?;
        if !self.first {
            self.c.raw(b",")?;
        }
        self.first = false;
        self.c.json().serialize_str(key)?;
        self.c.raw(b":")?;
        v.serialize(&mut *self.c)
    }

    fn close(mut self, tail: &[u8]) -> Result<()> {
        if self.through {
            // every key written was smaller
            self.write_extra_before(None)?;
        } else if let Some((k, v)) = self.extra.take() {
            self.entries.push((k.to_string(), serde_json::to_vec(v)?));
        }
        // as a `Value` map: sorted by key, a repeated key keeps its last value
        let mut entries = std::mem::take(&mut self.entries);
        entries.sort_by(|a, b| a.0.cmp(&b.0));
        for k in 0..entries.len() {
            if entries.get(k + 1).is_some_and(|next| next.0 == entries[k].0) {
                continue;
            }
            let (key, value) = &entries[k];
            self.write_entry(key, value)?;
        }
        self.c.raw(b"}")?;
        self.c.raw(tail)
    }
}

macro_rules! through {
    ($($f:ident: $t:ty),*) => {$(
        fn $f(self, v: $t) -> Result<()> {
            self.json().$f(v)
        }
    )*};
}

impl<'a, 's, W: Write> ser::Serializer for &'a mut Canonical<'s, W> {
    type Ok = ();
    type Error = Error;
    type SerializeSeq = Array<'a, 's, W>;
    type SerializeTuple = Array<'a, 's, W>;
    type SerializeTupleStruct = Array<'a, 's, W>;
    type SerializeTupleVariant = Array<'a, 's, W>;
    type SerializeMap = Object<'a, 's, W>;
    type SerializeStruct = Object<'a, 's, W>;
    type SerializeStructVariant = Object<'a, 's, W>;

    through!(serialize_bool: bool, serialize_i8: i8, serialize_i16: i16, serialize_i32: i32, serialize_i64: i64,
        serialize_u8: u8, serialize_u16: u16, serialize_u32: u32, serialize_u64: u64, serialize_f64: f64,
        serialize_str: &str, serialize_bytes: &[u8]);

    fn serialize_i128(self, v: i128) -> Result<()> {
        // as `Value` holds it: a u64 or an i64, else refused
        match (u64::try_from(v), i64::try_from(v)) {
            (Ok(u), _) => self.serialize_u64(u),
            (_, Ok(i)) => self.serialize_i64(i),
            _ => Err(ser::Error::custom("number out of range")),
        }
    }
    fn serialize_u128(self, v: u128) -> Result<()> {
        match u64::try_from(v) {
            Ok(u) => self.serialize_u64(u),
            _ => Err(ser::Error::custom("number out of range")),
        }
    }
    fn serialize_f32(self, v: f32) -> Result<()> {
        // `Value` widens an f32 to an f64
        self.serialize_f64(v as f64)
    }
    fn serialize_char(self, v: char) -> Result<()> {
        self.serialize_str(v.encode_utf8(&mut [0; 4]))
    }
    fn serialize_none(self) -> Result<()> {
        self.raw(b"null")
    }
    fn serialize_some<T: ?Sized + Serialize>(self, v: &T) -> Result<()> {
        v.serialize(self)
    }
    fn serialize_unit(self) -> Result<()> {
        self.raw(b"null")
    }
    fn serialize_unit_struct(self, _: &'static str) -> Result<()> {
        self.raw(b"null")
    }
    fn serialize_unit_variant(self, _: &'static str, _: u32, variant: &'static str) -> Result<()> {
        self.serialize_str(variant)
    }
    fn serialize_newtype_struct<T: ?Sized + Serialize>(self, _: &'static str, v: &T) -> Result<()> {
        v.serialize(self)
    }
    fn serialize_newtype_variant<T: ?Sized + Serialize>(
        self,
        _: &'static str,
        _: u32,
        variant: &'static str,
        v: &T,
    ) -> Result<()> {
        self.variant_head(variant)?;
        v.serialize(&mut *self)?;
        self.raw(b"}")
    }
    fn serialize_seq(self, _: Option<usize>) -> Result<Array<'a, 's, W>> {
        self.extra = None;
        self.raw(b"[")?;
        Ok(Array { c: self, first: true, close: b"]" })
    }
    fn serialize_tuple(self, len: usize) -> Result<Array<'a, 's, W>> {
        self.serialize_seq(Some(len))
    }
    fn serialize_tuple_struct(self, _: &'static str, len: usize) -> Result<Array<'a, 's, W>> {
        self.serialize_seq(Some(len))
    }
    fn serialize_tuple_variant(
        self,
        _: &'static str,
        _: u32,
        variant: &'static str,
        _: usize,
    ) -> Result<Array<'a, 's, W>> {
        self.variant_head(variant)?;
        self.raw(b"[")?;
        Ok(Array { c: self, first: true, close: b"]}" })
    }
    fn serialize_map(self, _: Option<usize>) -> Result<Object<'a, 's, W>> {
        self.open(false)
    }
    fn serialize_struct(self, name: &'static str, _: usize) -> Result<Object<'a, 's, W>> {
        let through = self.sorted.contains(&name);
        self.open(through)
    }
    fn serialize_struct_variant(
        self,
        _: &'static str,
        _: u32,
        variant: &'static str,
        _: usize,
    ) -> Result<Object<'a, 's, W>> {
        self.variant_head(variant)?;
        // the closing `}` of the variant's object is written by `end`
        self.open(false)
    }
}

/// The sequence-like serde traits: each element written after the other, then the close.
macro_rules! array_serializers {
    ($($kind:ident::$element:ident),*) => {$(
        impl<W: Write> ser::$kind for Array<'_, '_, W> {
            type Ok = ();
            type Error = Error;
            fn $element<T: ?Sized + Serialize>(&mut self, v: &T) -> Result<()> {
                self.element(v)
            }
            fn end(self) -> Result<()> {
                self.close()
            }
        }
    )*};
}

array_serializers!(
    SerializeSeq::serialize_element,
    SerializeTuple::serialize_element,
    SerializeTupleStruct::serialize_field,
    SerializeTupleVariant::serialize_field
);

impl<W: Write> ser::SerializeMap for Object<'_, '_, W> {
    type Ok = ();
    type Error = Error;
    fn serialize_key<T: ?Sized + Serialize>(&mut self, key: &T) -> Result<()> {
        self.key = Some(key_string(key)?);
        Ok(())
    }
    fn serialize_value<T: ?Sized + Serialize>(&mut self, v: &T) -> Result<()> {
        let key = self.key.take().ok_or_else(|| ser::Error::custom("a map value without its key"))?;
        let bytes = self.c.bytes_of(v)?;
        self.entries.push((key, bytes));
        Ok(())
    }
    fn end(self) -> Result<()> {
        self.close(b"")
    }
}

impl<W: Write> ser::SerializeStruct for Object<'_, '_, W> {
    type Ok = ();
    type Error = Error;
    fn serialize_field<T: ?Sized + Serialize>(&mut self, key: &'static str, v: &T) -> Result<()> {
        self.field(key, v)
    }
    fn end(self) -> Result<()> {
        self.close(b"")
    }
}

impl<W: Write> ser::SerializeStructVariant for Object<'_, '_, W> {
    type Ok = ();
    type Error = Error;
    fn serialize_field<T: ?Sized + Serialize>(&mut self, key: &'static str, v: &T) -> Result<()> {
        self.field(key, v)
    }
    fn end(self) -> Result<()> {
        self.close(b"}")
    }
}

/// A writer that hashes what it is given (SHA-256) and counts its bytes.
#[derive(Default)]
pub struct HashingWriter {
    hasher: sha2::Sha256,
    /// Bytes written.
    pub len: usize,
}

impl HashingWriter {
    /// The hex digest.
    pub fn hex(self) -> String {
        use sha2::Digest;
        self.hasher.finalize().iter().map(|b| format!("{b:02x}")).collect()
    }
}

impl Write for HashingWriter {
    fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
        use sha2::Digest;
        self.hasher.update(b);
        self.len += b.len();
        Ok(b.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

/// SHA-256 (hex) and length of the canonical JSON of `v`, streamed into the hash.
pub fn sha256_of<T: ?Sized + Serialize>(v: &T, sorted: &[&'static str]) -> Result<(String, usize)> {
    let mut w = std::io::BufWriter::with_capacity(1 << 16, HashingWriter::default());
    v.serialize(&mut Canonical::new(&mut w, sorted))?;
    let h = w.into_inner().map_err(|e| Error::io(e.into_error()))?;
    let len = h.len;
    Ok((h.hex(), len))
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde::Serialize;
    use std::collections::{BTreeMap, HashMap};

    #[derive(Serialize)]
    struct Sorted {
        a: u32,
        b: Vec<Unsorted>,
        c: Option<f64>,
    }

    #[derive(Serialize)]
    enum E {
        Unit,
        New(f32),
        Tuple(i8, String),
        Strukt { z: u8, y: char },
    }

    #[derive(Serialize)]
    struct Unsorted {
        zeta: f64,
        alpha: Option<String>,
        map: HashMap<String, i128>,
        nums: BTreeMap<u32, bool>,
        e: Vec<E>,
        bytes: serde_bytes_like::Bytes,
        unit: (),
        nested: Option<Box<Unsorted>>,
        tuple: (u8, f64, &'static str),
    }

    mod serde_bytes_like {
        pub struct Bytes(pub Vec<u8>);
        impl serde::Serialize for Bytes {
            fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                s.serialize_bytes(&self.0)
            }
        }
    }

    fn sample(depth: u32) -> Unsorted {
        Unsorted {
            zeta: f64::NAN,
            alpha: Some("q\"uo\\te\u{1}é".into()),
            map: [("b".to_string(), -5i128), ("a".to_string(), 1 << 40), ("ab".to_string(), 0)].into(),
            nums: [(10, true), (2, false)].into(),
            e: vec![E::Unit, E::New(0.1), E::Tuple(-3, "x".into()), E::Strukt { z: 1, y: 'ß' }],
            bytes: serde_bytes_like::Bytes(vec![0, 255, 7]),
            unit: (),
            nested: (depth > 0).then(|| Box::new(sample(depth - 1))),
            tuple: (1, -0.0, "t"),
        }
    }

    fn canonical<T: Serialize>(v: &T, sorted: &[&'static str]) -> Vec<u8> {
        let mut c = Canonical::new(Vec::new(), sorted);
        v.serialize(&mut c).unwrap();
        c.into_inner()
    }

    #[test]
    fn equals_the_bytes_of_a_value_tree() {
        let v = Sorted { a: 7, b: vec![sample(2), sample(0)], c: Some(1e-300) };
        let tree = serde_json::to_vec(&serde_json::to_value(&v).unwrap()).unwrap();
        assert_eq!(String::from_utf8(canonical(&v, &[])).unwrap(), String::from_utf8(tree.clone()).unwrap());
        // written through (its fields are declared sorted): the same bytes
        assert_eq!(canonical(&v, &["Sorted"]), tree);
        let (sum, len) = sha256_of(&v, &["Sorted"]).unwrap();
        assert_eq!((sum, len), (crate::fsutil::sha256_hex(&tree), tree.len()));
    }

    #[test]
    fn a_field_is_inserted_at_its_sorted_place() {
        let v = Sorted { a: 1, b: vec![], c: None };
        let mut tree = serde_json::to_value(&v).unwrap();
        tree["bb"] = serde_json::Value::String("x".into());
        let want = serde_json::to_vec(&tree).unwrap();
        for sorted in [&["Sorted"][..], &[]] {
            let mut c = Canonical::new(Vec::new(), sorted).with_field("bb", "x");
            v.serialize(&mut c).unwrap();
            assert_eq!(c.into_inner(), want);
        }
        tree["zz"] = serde_json::Value::String("y".into());
        let mut c = Canonical::new(Vec::new(), &["Sorted"]).with_field("zz", "y");
        let _ = tree.as_object_mut().unwrap().remove("bb");
        v.serialize(&mut c).unwrap();
        assert_eq!(c.into_inner(), serde_json::to_vec(&tree).unwrap());
    }

    #[test]
    fn a_struct_written_through_out_of_order_is_refused() {
        let mut c = Canonical::new(Vec::new(), &["Unsorted"]);
        let e = sample(0).serialize(&mut c).unwrap_err();
        assert!(e.to_string().contains("sorted order"), "{e}");
    }
}
