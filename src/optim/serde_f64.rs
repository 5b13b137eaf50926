//! Serde for `Vec<f64>` that keeps non-finite values (JSON has no ∞ or NaN): finite values
//! are numbers, others the strings "inf", "-inf", "nan".

use serde::de::{self, Deserializer, SeqAccess, Visitor};
use serde::ser::{SerializeSeq, Serializer};

/// Serialize.
pub fn serialize<S: Serializer>(v: &[f64], s: S) -> Result<S::Ok, S::Error> {
    let mut seq = s.serialize_seq(Some(v.len()))?;
    for x in v {
        if x.is_finite() {
            seq.serialize_element(x)?;
        } else if x.is_nan() {
            seq.serialize_element("nan")?;
        } else if *x > 0.0 {
            seq.serialize_element("inf")?;
        } else {
            seq.serialize_element("-inf")?;
        }
    }
    seq.end()
}

#[derive(serde::Deserialize)]
#[serde(untagged)]
enum Num {
    F(f64),
    S(String),
}

struct V;
impl<'de> Visitor<'de> for V {
    type Value = Vec<f64>;
    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("a list of numbers or \"inf\"/\"-inf\"/\"nan\"")
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut a: A) -> Result<Vec<f64>, A::Error> {
        let mut out = vec![];
        while let Some(n) = a.next_element::<Num>()? {
            out.push(match n {
                Num::F(x) => x,
                Num::S(s) => match s.as_str() {
                    "inf" => f64::INFINITY,
                    "-inf" => f64::NEG_INFINITY,
                    "nan" => f64::NAN,
                    other => return Err(de::Error::custom(format!("`{other}` is not a number"))),
                },
            });
        }
        Ok(out)
    }
}

/// Deserialize.
pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<f64>, D::Error> {
    d.deserialize_seq(V)
}

#[cfg(test)]
mod tests {
    #[derive(serde::Serialize, serde::Deserialize)]
    struct W(#[serde(with = "super")] Vec<f64>);

    #[test]
    fn every_float_round_trips_bit_exactly() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(2);
        let mut v: Vec<f64> = (0..20000).map(|_| f64::from_bits(rng.random::<u64>())).filter(|x| !x.is_nan()).collect();
        v.extend([
            f64::INFINITY,
            f64::NEG_INFINITY,
            0.0,
            -0.0,
            f64::MIN_POSITIVE,
            105.1438757555396,
            105.14387575553963,
        ]);
        let s = serde_json::to_string(&W(v.clone())).unwrap();
        let back: W = serde_json::from_str(&s).unwrap();
        for (a, b) in v.iter().zip(&back.0) {
            assert_eq!(a.to_bits(), b.to_bits(), "{a:e} -> {b:e}");
        }
        let n: W = serde_json::from_str("[\"nan\"]").unwrap();
        assert!(n.0[0].is_nan());
        assert!(serde_json::from_str::<W>("[\"abc\"]").is_err());
    }
}
