//! A second reading of a TOML document that did not deserialize, to find every problem
//! in it ([`super::problems`] drives it): a serde deserializer over the parsed document
//! (every value with its position) whose error ([`Found`]) keeps what serde reported in
//! pieces — the type expected and the value found, the unknown key and the keys known,
//! the missing field — with the dotted path it happened at (`pins[1].at`).
//!
//! Serde stops at the first error. So that the next reading gets past it, a reading
//! takes [`Fix`]es by path: a value found wrong or a missing field is read as a
//! stand-in (a value of whatever type is asked for: `1`, `""`, `false`, an empty list,
//! a table of stand-ins), an unknown key is left out.

use crate::scene::found::{join, Found, Seen, What};
use serde::de::{self, DeserializeSeed, IntoDeserializer, Unexpected, Visitor};
use std::cell::{Cell, RefCell};
use std::collections::{BTreeMap, BTreeSet};
use std::ops::Range;
use toml::de::{DeTable, DeValue};
use toml::Spanned;

/// What a reading does at a path.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Fix {
    /// Read a stand-in instead of the value (or the missing field).
    StandIn,
    /// Leave the key out.
    Drop,
}

/// The state one reading shares: the fixes, and what it learnt about the stand-ins.
pub(crate) struct Reading<'f> {
    fixes: &'f BTreeMap<String, Fix>,
    /// Paths of stand-ins read as tables (a missing table, not a missing value).
    pub tables: RefCell<BTreeSet<String>>,
    /// Whether a stand-in was read as "anything" (serde buffering an internally tagged
    /// table): its type then is a guess, and errors after it may be the guess's.
    pub guessed: Cell<bool>,
}

impl<'f> Reading<'f> {
    /// A reading with `fixes`.
    pub fn new(fixes: &'f BTreeMap<String, Fix>) -> Self {
        Self {
            fixes,
            tables: RefCell::default(),
            guessed: Cell::new(false),
        }
    }

    /// The deserializer of the whole document `root`.
    pub fn root<'a, 'i>(&'a self, root: &'a Spanned<DeValue<'i>>) -> Probe<'a, 'i> {
        Probe {
            reading: self,
            path: String::new(),
            node: Some(root),
        }
    }
}

/// The deserializer of one value at `path`; `node: None` is a stand-in.
pub(crate) struct Probe<'a, 'i> {
    reading: &'a Reading<'a>,
    path: String,
    node: Option<&'a Spanned<DeValue<'i>>>,
}

impl<'a, 'i> Probe<'a, 'i> {
    /// The deserializer of the value at `path` (`None`: a stand-in), as the fixes say.
    fn child(&self, path: String, node: Option<&'a Spanned<DeValue<'i>>>) -> Self {
        let node = node.filter(|_| self.reading.fixes.get(&path) != Some(&Fix::StandIn));
        Self {
            reading: self.reading,
            path,
            node,
        }
    }

    /// The same value, for the entries or items that read inside it.
    fn again(&self) -> Self {
        Self {
            reading: self.reading,
            path: self.path.clone(),
            node: self.node,
        }
    }

    fn span(&self) -> Option<Range<usize>> {
        self.node.map(|n| n.span())
    }

    /// The entries of this table (or of a stand-in of a struct with `fields`): its keys
    /// but the dropped ones, and stand-ins for the missing ones the fixes name.
    fn entries(&self, fields: &'static [&'static str]) -> Entries<'a, 'i> {
        let mut items = Vec::new();
        if let Some(DeValue::Table(table)) = self.node.map(|n| n.get_ref()) {
            for (key, value) in table.iter() {
                let path = join(&self.path, key.get_ref());
                if self.reading.fixes.get(&path) != Some(&Fix::Drop) {
                    items.push((key.get_ref().to_string(), Some(key.span()), Some(value)));
                }
            }
            let prefix = join(&self.path, "");
            for (path, fix) in self.reading.fixes.range(prefix.clone()..) {
                let Some(key) = path.strip_prefix(&prefix) else {
                    break;
                };
                let plain = !key.contains(['.', '[']);
                if plain && *fix == Fix::StandIn && !table.contains_key(key) {
                    items.push((key.to_string(), None, None));
                }
            }
        } else {
            items.extend(fields.iter().map(|f| (f.to_string(), None, None)));
        }
        Entries {
            parent: self.again(),
            items: items.into_iter(),
            value: None,
        }
    }

    /// The items of this array (`n` stand-ins for a stand-in).
    fn items(&self, n: usize) -> Items<'a, 'i> {
        let nodes: Vec<_> = match self.node.map(|n| n.get_ref()) {
            Some(DeValue::Array(array)) => array.iter().map(Some).collect(),
            _ => vec![None; n],
        };
        Items {
            parent: self.again(),
            nodes: nodes.into_iter().enumerate(),
            count: 0,
        }
    }

    /// The value as serde's [`Unexpected`] words it.
    fn unexpected(&self) -> Seen {
        match self.node.map(|n| n.get_ref()) {
            None => Seen::Other("nothing".into()),
            Some(DeValue::String(s)) => Seen::Str(s.to_string()),
            Some(DeValue::Integer(i)) => match integer(i) {
                Some(n) => Seen::Integer(n),
                None => Seen::Other(format!("the integer {i}")),
            },
            Some(DeValue::Float(x)) => Seen::Float(x.as_str().parse().unwrap_or(f64::NAN)),
            Some(DeValue::Boolean(b)) => Seen::Bool(*b),
            Some(DeValue::Datetime(d)) => Seen::Other(format!("the date {d}")),
            Some(DeValue::Array(_)) => Seen::Other("a list".into()),
            Some(DeValue::Table(_)) => Seen::Other("a table".into()),
        }
    }

    fn mismatch(&self, expected: String) -> Found {
        Found::new(What::Mismatch {
            expected,
            found: self.unexpected(),
        })
        .at(&self.path, self.span())
    }
}

/// A TOML integer's value (`None` beyond 128 bits).
fn integer(i: &toml::de::DeInteger<'_>) -> Option<i128> {
    i128::from_str_radix(i.as_str(), i.radix()).ok()
}

/// The stand-in's reading of a scalar type, else the value's.
macro_rules! scalar {
    ($($method:ident($v:ident) => $stand_in:expr;)*) => {$(
        fn $method<V: Visitor<'de>>(self, $v: V) -> Result<V::Value, Found> {
            match self.node {
                None => $stand_in,
                Some(_) => self.deserialize_any($v),
            }
        }
    )*};
}

impl<'de> de::Deserializer<'de> for Probe<'_, '_> {
    type Error = Found;

    fn deserialize_any<V: Visitor<'de>>(self, v: V) -> Result<V::Value, Found> {
        let (path, span) = (self.path.clone(), self.span());
        let Some(node) = self.node else {
            self.reading.guessed.set(true);
            return v.visit_u64(1);
        };
        let read = match node.get_ref() {
            DeValue::String(s) => v.visit_str(s),
            DeValue::Integer(i) => match integer(i) {
                Some(n) => match (i64::try_from(n), u64::try_from(n)) {
                    (Ok(n), _) => v.visit_i64(n),
                    (_, Ok(n)) => v.visit_u64(n),
                    _ => v.visit_i128(n),
                },
                None => Err(self.mismatch("a number of at most 128 bits".into())),
            },
            DeValue::Float(x) => match x.as_str().parse::<f64>() {
                Ok(x) => v.visit_f64(x),
                Err(_) => Err(self.mismatch("a number".into())),
            },
            DeValue::Boolean(b) => v.visit_bool(*b),
            DeValue::Datetime(d) => {
                let date = format!("the date {d}");
                Err(de::Error::invalid_type(Unexpected::Other(&date), &v))
            }
            DeValue::Array(_) => {
                let mut items = self.items(0);
                v.visit_seq(&mut items)
                    .and_then(|value| items.end().map(|()| value))
            }
            DeValue::Table(_) => v.visit_map(self.entries(&[])),
        };
        read.map_err(|e| e.at(&path, span))
    }

    scalar! {
        deserialize_bool(v) => v.visit_bool(false);
        deserialize_i8(v) => v.visit_i64(1);
        deserialize_i16(v) => v.visit_i64(1);
        deserialize_i32(v) => v.visit_i64(1);
        deserialize_i64(v) => v.visit_i64(1);
        deserialize_u8(v) => v.visit_u64(1);
        deserialize_u16(v) => v.visit_u64(1);
        deserialize_u32(v) => v.visit_u64(1);
        deserialize_u64(v) => v.visit_u64(1);
        deserialize_f32(v) => v.visit_f64(1.0);
        deserialize_f64(v) => v.visit_f64(1.0);
        deserialize_char(v) => v.visit_char('x');
        deserialize_str(v) => v.visit_str("");
        deserialize_string(v) => v.visit_str("");
        deserialize_identifier(v) => v.visit_str("");
        deserialize_bytes(v) => v.visit_bytes(&[]);
        deserialize_byte_buf(v) => v.visit_bytes(&[]);
        deserialize_unit(v) => v.visit_unit();
    }

    fn deserialize_option<V: Visitor<'de>>(self, v: V) -> Result<V::Value, Found> {
        match self.node {
            None => v.visit_none(),
            Some(_) => v.visit_some(self),
        }
    }

    fn deserialize_unit_struct<V: Visitor<'de>>(
        self,
        _name: &'static str,
        v: V,
    ) -> Result<V::Value, Found> {
        self.deserialize_unit(v)
    }

    fn deserialize_newtype_struct<V: Visitor<'de>>(
        self,
        _name: &'static str,
        v: V,
    ) -> Result<V::Value, Found> {
        v.visit_newtype_struct(self)
    }

    fn deserialize_seq<V: Visitor<'de>>(self, v: V) -> Result<V::Value, Found> {
        self.deserialize_tuple(0, v)
    }

    fn deserialize_tuple<V: Visitor<'de>>(self, len: usize, v: V) -> Result<V::Value, Found> {
        let (path, span) = (self.path.clone(), self.span());
        match self.node.map(|n| n.get_ref()) {
            None | Some(DeValue::Array(_)) => {
                let mut items = self.items(len);
                let value = v
                    .visit_seq(&mut items)
                    .map_err(|e| e.at(&path, span.clone()))?;
                items.end()?;
                Ok(value)
            }
            Some(_) => self.deserialize_any(v),
        }
    }

    fn deserialize_tuple_struct<V: Visitor<'de>>(
        self,
        _name: &'static str,
        len: usize,
        v: V,
    ) -> Result<V::Value, Found> {
        self.deserialize_tuple(len, v)
    }

    fn deserialize_map<V: Visitor<'de>>(self, v: V) -> Result<V::Value, Found> {
        self.deserialize_struct("", &[], v)
    }

    fn deserialize_struct<V: Visitor<'de>>(
        self,
        _name: &'static str,
        fields: &'static [&'static str],
        v: V,
    ) -> Result<V::Value, Found> {
        let (path, span) = (self.path.clone(), self.span());
        match self.node.map(|n| n.get_ref()) {
            None | Some(DeValue::Table(_)) => {
                if self.node.is_none() {
                    self.reading.tables.borrow_mut().insert(path.clone());
                }
                v.visit_map(self.entries(fields))
                    .map_err(|e| e.at(&path, span))
            }
            Some(_) => self.deserialize_any(v),
        }
    }

    fn deserialize_enum<V: Visitor<'de>>(
        self,
        _name: &'static str,
        variants: &'static [&'static str],
        v: V,
    ) -> Result<V::Value, Found> {
        let (path, span) = (self.path.clone(), self.span());
        let name = match self.node.map(|n| n.get_ref()) {
            None => variants.first().copied().unwrap_or_default(),
            Some(DeValue::String(s)) => s.as_ref(),
            Some(_) => return Err(self.mismatch(super::problems::one_of(variants))),
        };
        let name: de::value::StrDeserializer<'_, Found> = name.into_deserializer();
        v.visit_enum(name).map_err(|e| e.at(&path, span))
    }

    fn deserialize_ignored_any<V: Visitor<'de>>(self, v: V) -> Result<V::Value, Found> {
        v.visit_unit()
    }
}

/// A key, its span (none for a stand-in's) and its value (`None`: a stand-in).
type Entry<'a, 'i> = (
    String,
    Option<Range<usize>>,
    Option<&'a Spanned<DeValue<'i>>>,
);

/// The entries of a table, as a [`de::MapAccess`].
struct Entries<'a, 'i> {
    parent: Probe<'a, 'i>,
    items: std::vec::IntoIter<Entry<'a, 'i>>,
    /// The value of the key last read, and its path.
    value: Option<(String, Option<&'a Spanned<DeValue<'i>>>)>,
}

impl<'de> de::MapAccess<'de> for Entries<'_, '_> {
    type Error = Found;

    fn next_key_seed<K: DeserializeSeed<'de>>(
        &mut self,
        seed: K,
    ) -> Result<Option<K::Value>, Found> {
        let Some((key, span, node)) = self.items.next() else {
            return Ok(None);
        };
        let path = &self.parent.path;
        let read = seed.deserialize(key.as_str().into_deserializer());
        let read = read.map_err(|e: Found| {
            let mut e = e;
            if let What::Unknown { table, .. } = &mut e.what {
                *table = node.and_then(|n| brackets(n.get_ref()));
            }
            e.at(path, span.or_else(|| self.parent.span()))
        });
        self.value = Some((join(path, &key), node));
        read.map(Some)
    }

    fn next_value_seed<S: DeserializeSeed<'de>>(&mut self, seed: S) -> Result<S::Value, Found> {
        let Some((path, node)) = self.value.take() else {
            return Err(de::Error::custom("a value asked for before its key"));
        };
        let child = self.parent.child(path.clone(), node);
        let span = child.span().or_else(|| self.parent.span());
        seed.deserialize(child).map_err(|e| e.at(&path, span))
    }
}

/// `"[]"` for a table, `"[[]]"` for an array of tables, `None` for anything else.
fn brackets(value: &DeValue<'_>) -> Option<&'static str> {
    match value {
        DeValue::Table(_) => Some("[]"),
        DeValue::Array(a) if !a.is_empty() && a.iter().all(|v| v.get_ref().is_table()) => {
            Some("[[]]")
        }
        _ => None,
    }
}

/// The items of an array, as a [`de::SeqAccess`].
struct Items<'a, 'i> {
    parent: Probe<'a, 'i>,
    nodes: std::iter::Enumerate<std::vec::IntoIter<Option<&'a Spanned<DeValue<'i>>>>>,
    /// Items read.
    count: usize,
}

impl Items<'_, '_> {
    /// An error if the visitor left items unread (a fixed-length list given too many).
    fn end(self) -> Result<(), Found> {
        let left = self.nodes.len();
        if left == 0 || self.parent.node.is_none() {
            return Ok(());
        }
        let expected = format!("an array of length {}", self.count);
        let what = What::Length {
            expected,
            found: self.count + left,
        };
        Err(Found::new(what).at(&self.parent.path, self.parent.span()))
    }
}

impl<'de> de::SeqAccess<'de> for &mut Items<'_, '_> {
    type Error = Found;

    fn next_element_seed<T: DeserializeSeed<'de>>(
        &mut self,
        seed: T,
    ) -> Result<Option<T::Value>, Found> {
        let Some((i, node)) = self.nodes.next() else {
            return Ok(None);
        };
        self.count += 1;
        let path = format!("{}[{i}]", self.parent.path);
        let child = self.parent.child(path.clone(), node);
        let span = child.span().or_else(|| self.parent.span());
        seed.deserialize(child)
            .map(Some)
            .map_err(|e| e.at(&path, span))
    }

    fn size_hint(&self) -> Option<usize> {
        Some(self.nodes.len())
    }
}

/// A document's root as a value (for [`Reading::root`]).
pub(crate) fn root_value(root: Spanned<DeTable<'_>>) -> Spanned<DeValue<'_>> {
    let span = root.span();
    Spanned::new(span, DeValue::Table(root.into_inner()))
}
