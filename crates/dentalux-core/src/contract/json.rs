//! The JSON reader of the render contract: values with the key path that led to them, so
//! every error names its key (`shapes[2].radius`), and objects whose keys are read one by one
//! and whose unread keys are refused (a misspelt key is an error, not a silent default).

use crate::error::Error;
use crate::geometry::Vec3;
use serde_json::{Map, Value};

/// A decoder's result: errors are `Error::InvalidInput` naming the key path.
pub(super) type R<T> = Result<T, Error>;

/// The error `msg`.
pub(super) fn bad<T>(msg: String) -> R<T> {
    Err(Error::InvalidInput(msg))
}

/// A JSON value with the key path that led to it.
#[derive(Clone, Copy)]
pub(super) struct Node<'a> {
    pub(super) v: &'a Value,
    pub(super) path: &'a str,
}

/// An object whose keys are read one by one; unknown keys are refused at the end.
pub(super) struct Obj<'a> {
    map: &'a Map<String, Value>,
    pub(super) path: String,
    seen: Vec<&'static str>,
}

/// How a JSON value reads in a message ("a number", "a list").
fn kind(v: &Value) -> &'static str {
    match v {
        Value::Null => "null",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Array(_) => "a list",
        Value::Object(_) => "an object",
    }
}

impl<'a> Node<'a> {
    pub(super) fn num(self) -> R<f64> {
        match self.v.as_f64() {
            Some(x) if x.is_finite() => Ok(x),
            _ => bad(format!(
                "{}: expected a finite number, got {}",
                self.path,
                kind(self.v)
            )),
        }
    }
    pub(super) fn uint(self) -> R<u64> {
        self.v.as_u64().map_or_else(
            || {
                bad(format!(
                    "{}: expected a non-negative integer, got {}",
                    self.path, self.v
                ))
            },
            Ok,
        )
    }
    pub(super) fn boolean(self) -> R<bool> {
        self.v.as_bool().map_or_else(
            || {
                bad(format!(
                    "{}: expected true or false, got {}",
                    self.path,
                    kind(self.v)
                ))
            },
            Ok,
        )
    }
    pub(super) fn string(self) -> R<&'a str> {
        self.v.as_str().map_or_else(
            || {
                bad(format!(
                    "{}: expected a string, got {}",
                    self.path,
                    kind(self.v)
                ))
            },
            Ok,
        )
    }
    pub(super) fn list(self) -> R<&'a [Value]> {
        match self.v {
            Value::Array(a) => Ok(a),
            _ => bad(format!(
                "{}: expected a list, got {}",
                self.path,
                kind(self.v)
            )),
        }
    }
    pub(super) fn obj(self) -> R<Obj<'a>> {
        match self.v {
            Value::Object(m) => Ok(Obj {
                map: m,
                path: self.path.to_string(),
                seen: Vec::new(),
            }),
            _ => bad(format!(
                "{}: expected an object, got {}",
                self.path,
                kind(self.v)
            )),
        }
    }
    pub(super) fn fixed<const N: usize>(self) -> R<[f64; N]> {
        let a = self.list()?;
        if a.len() != N {
            return bad(format!(
                "{}: expected a list of {N} numbers, got {} entries",
                self.path,
                a.len()
            ));
        }
        let mut out = [0.0; N];
        for (i, v) in a.iter().enumerate() {
            out[i] = Node {
                v,
                path: &format!("{}[{i}]", self.path),
            }
            .num()?;
        }
        Ok(out)
    }
    pub(super) fn vec3(self) -> R<Vec3> {
        self.fixed::<3>().map(Vec3::from_array)
    }
}

impl Obj<'_> {
    pub(super) fn key(&self, k: &str) -> String {
        if self.path.is_empty() {
            k.to_string()
        } else {
            format!("{}.{k}", self.path)
        }
    }
    /// The value at `k` (None when absent or null) and its path.
    pub(super) fn opt(&mut self, k: &'static str) -> Option<(&Value, String)> {
        self.seen.push(k);
        match self.map.get(k) {
            None | Some(Value::Null) => None,
            Some(v) => Some((v, self.key(k))),
        }
    }
    pub(super) fn req(&mut self, k: &'static str) -> R<(&Value, String)> {
        let path = self.key(k);
        self.opt(k)
            .map_or_else(|| bad(format!("{path} is missing (required)")), Ok)
    }
    pub(super) fn num(&mut self, k: &'static str) -> R<f64> {
        let (v, p) = self.req(k)?;
        Node { v, path: &p }.num()
    }
    /// `read` of the value at `k`, or None when it is absent or null.
    pub(super) fn opt_with<T>(
        &mut self,
        k: &'static str,
        read: impl FnOnce(Node<'_>) -> R<T>,
    ) -> R<Option<T>> {
        match self.opt(k) {
            Some((v, p)) => read(Node { v, path: &p }).map(Some),
            None => Ok(None),
        }
    }
    pub(super) fn num_or(&mut self, k: &'static str, default: f64) -> R<f64> {
        Ok(self.opt_with(k, |n| n.num())?.unwrap_or(default))
    }
    pub(super) fn opt_num(&mut self, k: &'static str) -> R<Option<f64>> {
        self.opt_with(k, |n| n.num())
    }
    pub(super) fn uint(&mut self, k: &'static str) -> R<u64> {
        let (v, p) = self.req(k)?;
        Node { v, path: &p }.uint()
    }
    pub(super) fn uint_or(&mut self, k: &'static str, default: u64) -> R<u64> {
        Ok(self.opt_with(k, |n| n.uint())?.unwrap_or(default))
    }
    pub(super) fn index(&mut self, k: &'static str, len: usize, what: &str) -> R<u32> {
        let (v, p) = self.req(k)?;
        let i = Node { v, path: &p }.uint()?;
        if i as usize >= len {
            return bad(format!(
                "{p} = {i} is out of range: {len} {what} defined (indices 0..{len})"
            ));
        }
        Ok(i as u32)
    }
    pub(super) fn string(&mut self, k: &'static str) -> R<String> {
        let (v, p) = self.req(k)?;
        Node { v, path: &p }.string().map(str::to_string)
    }
    pub(super) fn vec3(&mut self, k: &'static str) -> R<Vec3> {
        let (v, p) = self.req(k)?;
        Node { v, path: &p }.vec3()
    }
    pub(super) fn positive(&mut self, k: &'static str, unit: &str) -> R<f64> {
        let p = self.key(k);
        let x = self.num(k)?;
        crate::error::check_range(&p, x, 0.0, true, f64::INFINITY, true, unit)?;
        Ok(x)
    }
    pub(super) fn nonneg(&mut self, k: &'static str) -> R<f64> {
        let p = self.key(k);
        let x = self.num(k)?;
        crate::error::check_range(&p, x, 0.0, false, f64::INFINITY, true, "")?;
        Ok(x)
    }
    /// Refuse keys not read.
    pub(super) fn done(self) -> R<()> {
        for k in self.map.keys() {
            if !self.seen.contains(&k.as_str()) {
                let mut allowed = self.seen.clone();
                allowed.sort_unstable();
                allowed.dedup();
                return bad(format!(
                    "{}: unknown key; allowed: {}",
                    self.key(k),
                    allowed.join(", ")
                ));
            }
        }
        Ok(())
    }
}

/// The list at `k` (empty when absent or null), each entry with its path.
pub(super) fn list_of<'a>(o: &mut Obj<'a>, k: &'static str) -> R<Vec<(&'a Value, String)>> {
    let map: &'a Map<String, Value> = o.map;
    let path = o.key(k);
    o.seen.push(k);
    match map.get(k) {
        None | Some(Value::Null) => Ok(Vec::new()),
        Some(Value::Array(a)) => Ok(a
            .iter()
            .enumerate()
            .map(|(i, v)| (v, format!("{path}[{i}]")))
            .collect()),
        Some(v) => bad(format!("{path}: expected a list, got {}", kind(v))),
    }
}
