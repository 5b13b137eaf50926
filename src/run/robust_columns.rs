//! The robust columns of pareto.csv, archive.csv and population.csv (issue 22): for a robust
//! problem, after the design columns, `scenarios_run` and `scenarios_saved` (early stop),
//! then per object `NAME.p_stay`, its Clopper–Pearson interval `NAME.p_stay_lo`/`_hi`,
//! `NAME.stays` of `NAME.scenarios`, the worst free-object displacement and the object's
//! own objectives. A single-object problem has none (its files are as before, byte for byte).

/// A column: name, unit, meaning (`outputs::Column`).
type Column = (&'static str, &'static str, &'static str);
use crate::eval::Record;
use serde::de::{MapAccess, Visitor};
use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// The design-level robust columns.
pub const ROBUST_COLUMNS: [Column; 2] = [
    ("scenarios_run", "-", "scenarios simulated for this design (all objects)"),
    ("scenarios_saved", "-", "scenarios early stop did not need (an object's P(stay) >= p_min could no longer hold)"),
];

/// The per-object robust columns, each `NAME.column`.
pub const OBJECT_COLUMNS: [Column; 10] = [
    ("p_stay", "-", "P(object barely moves) over its scenarios run (constraint: >= p_min)"),
    ("p_stay_lo", "-", "Clopper-Pearson lower end of p_stay at the problem's confidence"),
    ("p_stay_hi", "-", "Clopper-Pearson upper end"),
    ("stays", "-", "scenarios in which the object stayed"),
    ("scenarios", "-", "scenarios run on this object"),
    ("max_displacement", "m", "worst displacement of the free object over its scenarios"),
    ("max_offset", "m", "max_offset on this object (stage 2, nominal inputs)"),
    ("alpha", "-", "alpha on this object"),
    ("mean_force", "N", "mean force on this object"),
    ("t_stab", "s", "t_stab aggregated over this object's scenarios"),
];

/// The design-level columns a certified design adds (pareto.csv of a robust run that
/// certifies its front, issue 41): its objective columns are then the fresh estimate.
pub const CERTIFIED_COLUMNS: [Column; 2] = [
    ("cert_scenarios", "-", "fresh scenarios its certification ran (all objects; objectives estimated on them)"),
    ("search_t_stab", "s", "t_stab aggregated over the search's scenarios (t_stab: over the fresh ones)"),
];

/// The per-object columns a certified design adds, each `NAME.column`.
pub const CERTIFIED_OBJECT_COLUMNS: [Column; 3] = [
    ("cert_stays", "-", "fresh scenarios of the certification in which the object stayed"),
    ("cert_scenarios", "-", "fresh scenarios of the certification on this object"),
    ("p_stay_lower", "-", "one-sided lower confidence bound on P(stay) from them (certified: >= p_min)"),
];

/// Whether `c` names a robust column of a design table: a design-level one, or an object's
/// `NAME.column` (the search's or a certified design's).
pub fn is_robust_column(c: &str) -> bool {
    ROBUST_COLUMNS.iter().chain(&CERTIFIED_COLUMNS).any(|r| r.0 == c)
        || c.rsplit_once('.').is_some_and(|(o, col)| {
            !o.is_empty() && OBJECT_COLUMNS.iter().chain(&CERTIFIED_OBJECT_COLUMNS).any(|r| r.0 == col)
        })
}

/// The robust cells of a row, in column order (empty for a single-object problem).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RobustColumns(pub Vec<(String, Option<f64>)>);

impl RobustColumns {
    /// The cells of a record.
    pub fn of(r: &Record) -> Self {
        let Some(rb) = &r.robust else { return RobustColumns::default() };
        let n = |v: usize| Some(v as f64);
        let mut c = vec![
            ("scenarios_run".to_string(), n(rb.scenarios_run)),
            ("scenarios_saved".to_string(), n(rb.scenarios_saved)),
        ];
        for o in &rb.objects {
            let vals = [
                o.p_stay,
                o.p_stay_lo,
                o.p_stay_hi,
                n(o.stays),
                n(o.scenarios),
                o.max_displacement,
                o.objectives.max_offset.filter(|m| *m >= 0.0),
                o.objectives.alpha,
                o.objectives.mean_force,
                o.objectives.t_stab,
            ];
            for (col, v) in OBJECT_COLUMNS.iter().zip(vals) {
                c.push((format!("{}.{}", o.name, col.0), v));
            }
        }
        RobustColumns(c)
    }

    /// These cells with a certified design's: the design-level certification columns after
    /// the search's, then each object's after its own (`search_t_stab`: the search's
    /// aggregated t_stab, the row's objective now the fresh estimate).
    pub fn with_certification(self, c: &crate::eval::CertificationRecord, search_t_stab: Option<f64>) -> Self {
        let n = |v: usize| Some(v as f64);
        let mut out = vec![];
        let mut cells = self.0.into_iter().peekable();
        while let Some((k, _)) = cells.peek() {
            if k.contains('.') {
                break;
            }
            out.push(cells.next().expect("peeked"));
        }
        out.push(("cert_scenarios".into(), n(c.scenarios_run)));
        out.push(("search_t_stab".into(), search_t_stab));
        for o in &c.objects {
            let prefix = format!("{}.", o.name);
            while let Some((k, _)) = cells.peek() {
                if !k.starts_with(&prefix) {
                    break;
                }
                out.push(cells.next().expect("peeked"));
            }
            let vals = [n(o.stays), n(o.scenarios), Some(o.p_stay_lower)];
            for (col, v) in CERTIFIED_OBJECT_COLUMNS.iter().zip(vals) {
                out.push((format!("{prefix}{}", col.0), v));
            }
        }
        out.extend(cells);
        RobustColumns(out)
    }

    /// The value of `column` of object `object` (None: not computed or no such column).
    pub fn get(&self, object: &str, column: &str) -> Option<f64> {
        let key = format!("{object}.{column}");
        self.0.iter().find(|(k, _)| *k == key).and_then(|c| c.1)
    }

    /// The object names, in column order.
    pub fn objects(&self) -> Vec<String> {
        let mut names: Vec<String> = vec![];
        for (k, _) in &self.0 {
            if let Some((o, _)) = k.split_once('.') {
                if names.last().map(String::as_str) != Some(o) {
                    names.push(o.to_string());
                }
            }
        }
        names
    }

    /// Whether `key` is one of these columns holding a measured value, not a count: an
    /// object's `p_stay`, `p_stay_lo`, `p_stay_hi`, `max_displacement` and objectives (the
    /// CSV writes them with a decimal point, see [`float_cell`]).
    pub fn is_float(&self, key: &str) -> bool {
        const COUNTS: [&str; 6] =
            ["scenarios_run", "scenarios_saved", "stays", "scenarios", "cert_stays", "cert_scenarios"];
        let base = key.rsplit('.').next().unwrap_or(key);
        !COUNTS.contains(&base) && self.0.iter().any(|(k, _)| k == key)
    }

    /// The columns with units and meanings (for a CSV's `#` header).
    pub fn columns(&self) -> Vec<(String, &'static str)> {
        self.0.iter().map(|(k, _)| (k.clone(), robust_unit(k).unwrap_or("-"))).collect()
    }
}

/// A float's CSV cell (Rust's `{}`: `0`, `1`, `0.25`, `NaN`) with a decimal point where it
/// has none (`0.0`, `1.0`), so that a column of whole values still reads as floats (pandas'
/// `read_csv` types a column of `0` as int64). Empty and non-finite cells stay as they are.
pub fn float_cell(cell: &mut String) {
    if !cell.is_empty() && cell.bytes().all(|b| b.is_ascii_digit() || b == b'-') {
        cell.push_str(".0");
    }
}

/// One CSV line of `row` (as `cells::line` writes it) with the cells of the columns that
/// `is_float` names written by [`float_cell`].
pub(crate) fn line_with_floats<T: Serialize + ?Sized>(row: &T, is_float: impl Fn(&str) -> bool) -> String {
    let mut cells = crate::cells::cells(row, crate::cells::Floats::Display);
    for (k, v) in &mut cells {
        if is_float(k) {
            float_cell(v);
        }
    }
    let mut s = cells.into_iter().map(|(_, c)| c).collect::<Vec<_>>().join(",");
    s.push('\n');
    s
}

/// The unit of robust column `name`: a design-level one, or an object's `NAME.column`
/// (None: not a robust column).
pub fn robust_unit(name: &str) -> Option<&'static str> {
    let base = name.rsplit('.').next().unwrap_or(name);
    let columns = ROBUST_COLUMNS.iter().chain(&OBJECT_COLUMNS).chain(&CERTIFIED_COLUMNS);
    columns.chain(&CERTIFIED_OBJECT_COLUMNS).find(|c| c.0 == base).map(|c| c.1)
}

impl Serialize for RobustColumns {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut m = s.serialize_map(Some(self.0.len()))?;
        for (k, v) in &self.0 {
            m.serialize_entry(k, v)?;
        }
        m.end()
    }
}

/// A cell read back: a number, or empty.
struct CellNumber(Option<f64>);

impl<'de> Deserialize<'de> for CellNumber {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = CellNumber;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a number or an empty cell")
            }
            fn visit_f64<E>(self, v: f64) -> Result<CellNumber, E> {
                Ok(CellNumber(Some(v)))
            }
            fn visit_u64<E>(self, v: u64) -> Result<CellNumber, E> {
                Ok(CellNumber(Some(v as f64)))
            }
            fn visit_i64<E>(self, v: i64) -> Result<CellNumber, E> {
                Ok(CellNumber(Some(v as f64)))
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<CellNumber, E> {
                if v.is_empty() {
                    return Ok(CellNumber(None));
                }
                v.parse().map(|x| CellNumber(Some(x))).map_err(|_| E::custom(format!("not a number: {v:?}")))
            }
            fn visit_unit<E>(self) -> Result<CellNumber, E> {
                Ok(CellNumber(None))
            }
            fn visit_none<E>(self) -> Result<CellNumber, E> {
                Ok(CellNumber(None))
            }
            fn visit_some<D: Deserializer<'de>>(self, d: D) -> Result<CellNumber, D::Error> {
                CellNumber::deserialize(d)
            }
        }
        d.deserialize_any(V)
    }
}

impl<'de> Deserialize<'de> for RobustColumns {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = RobustColumns;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("the robust columns")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut m: A) -> Result<RobustColumns, A::Error> {
                let mut out = vec![];
                while let Some((k, v)) = m.next_entry::<String, CellNumber>()? {
                    out.push((k, v.0));
                }
                Ok(RobustColumns(out))
            }
        }
        d.deserialize_map(V)
    }
}
