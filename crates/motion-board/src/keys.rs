//! A board's own config keys: how its crate reads and validates the keys of a `[[device]]`
//! or `[[axis]]` table that are not the server's general ones, with located errors.
//!
//! The server splits every `[[device]]` and `[[axis]]` table of the file into its general
//! keys (name, link, model, units, limits, the general `home` keys, …) and the rest, the
//! board's [`KeyTable`]; it refuses a key no board of that model has (naming the models
//! that have it) before the board sees it. The board deserializes its table into its own
//! serde struct ([`KeyTable::parse`]: `toml::Spanned` fields keep their place in the
//! file, integers as [`Int`] so that a value beyond 64 bits is a range error), validates
//! the values, and reports every problem through [`KeyIssues`] with the value's span and
//! its key (`device[0].switchover_ms`): the server turns them into `file:line:column`.

use core::fmt;
use core::ops::{Range, RangeInclusive};

use serde::Deserialize;
pub use toml::Spanned;
use toml::de::{DeTable, DeValue};

/// A byte range of the config file.
pub type Span = Range<usize>;

/// An integer as written, whatever its size: a value beyond 64 bits is a range error
/// reported by validation with its key and allowed range, not a parse error.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Int(pub i128);

impl<'de> Deserialize<'de> for Int {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct Visitor;
        impl serde::de::Visitor<'_> for Visitor {
            type Value = Int;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("an integer")
            }
            fn visit_i64<E>(self, v: i64) -> Result<Int, E> {
                Ok(Int(i128::from(v)))
            }
            fn visit_u64<E>(self, v: u64) -> Result<Int, E> {
                Ok(Int(i128::from(v)))
            }
            fn visit_i128<E>(self, v: i128) -> Result<Int, E> {
                Ok(Int(v))
            }
            fn visit_u128<E>(self, v: u128) -> Result<Int, E> {
                Ok(Int(i128::try_from(v).unwrap_or(i128::MAX)))
            }
        }
        deserializer.deserialize_any(Visitor)
    }
}

impl Int {
    /// The value, saturated to `i64` (range checks see a saturated value out of range too).
    #[must_use]
    pub fn get(&self) -> i64 {
        i64::try_from(self.0).unwrap_or(if self.0 < 0 { i64::MIN } else { i64::MAX })
    }
}

impl fmt::Display for Int {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.0.fmt(f)
    }
}

/// A raw integer key of either representation.
pub trait IntValue {
    /// The value, widened.
    fn wide(&self) -> i128;
}

impl IntValue for i64 {
    fn wide(&self) -> i128 {
        i128::from(*self)
    }
}

impl IntValue for Int {
    fn wide(&self) -> i128 {
        self.0
    }
}

/// Where a board reports what is wrong with its keys (the server's validator). Boards
/// call the inherent methods of `dyn KeyIssues` ([`issue`](#method.issue),
/// [`warn`](#method.warn), [`int_in`](#method.int_in), [`one_of`](#method.one_of)).
pub trait KeyIssues {
    /// `message` about `key` (dotted: `axis[2].current.peak`) at `span`: the file is
    /// refused.
    fn report_issue(&mut self, span: Span, key: &str, message: String);

    /// A warning about `key` at `span`: the file is used, and the warning printed.
    fn report_warning(&mut self, span: Span, key: &str, message: String);

    /// A value the TOML deserializer refused (wrong type, unknown key) at `span`, in its
    /// words: the server names the key from the span.
    fn report_refused(&mut self, span: Span, message: &str);
}

impl dyn KeyIssues + '_ {
    /// `message` about `key` at `span`: the file is refused.
    pub fn issue(&mut self, span: Span, key: &str, message: impl Into<String>) {
        self.report_issue(span, key, message.into());
    }

    /// A warning about `key` at `span`.
    pub fn warn(&mut self, span: Span, key: &str, message: impl Into<String>) {
        self.report_warning(span, key, message.into());
    }

    /// `value` of a raw integer key when it lies in `range`; otherwise an issue naming the
    /// range (the shape the server's own keys report).
    pub fn int_in<T: IntValue>(
        &mut self,
        value: &Spanned<T>,
        key: &str,
        range: RangeInclusive<i64>,
    ) -> Option<i64> {
        let v = value.get_ref().wide();
        if (i128::from(*range.start())..=i128::from(*range.end())).contains(&v) {
            i64::try_from(v).ok()
        } else {
            self.issue(
                value.span(),
                key,
                format!(
                    "{v} is out of range; allowed: {}..={}",
                    range.start(),
                    range.end()
                ),
            );
            None
        }
    }

    /// `silence_ms` (every board that has it: how long the board may say nothing while it
    /// owes an answer before it is declared not answering), checked against
    /// [`SILENCE_RANGE_MS`](motion_drivers::SILENCE_RANGE_MS).
    pub fn silence_ms(&mut self, value: &Spanned<Int>, key: &str) -> Option<core::time::Duration> {
        let ms = self.int_in(value, key, motion_drivers::SILENCE_RANGE_MS)?;
        let ms = u64::try_from(ms).ok()?;
        if ms < 250 {
            self.warn(
                value.span(),
                key,
                format!(
                    "{ms} ms: a host that stalls longer (a loaded machine, a board's process \
                     without CPU) makes a healthy board look dead; default {} ms",
                    motion_drivers::DEFAULT_SILENCE.as_millis()
                ),
            );
        }
        Some(core::time::Duration::from_millis(ms))
    }

    /// `host_latency_ms` (every board that has it: how much later than on the wire an
    /// answer may reach the driver), checked against
    /// [`HOST_LATENCY_RANGE_MS`](motion_drivers::HOST_LATENCY_RANGE_MS); milliseconds.
    pub fn host_latency_ms(&mut self, value: &Spanned<f64>, key: &str) -> Option<f64> {
        let ms = *value.get_ref();
        if ms.is_finite() && motion_drivers::HOST_LATENCY_RANGE_MS.contains(&ms) {
            return Some(ms);
        }
        let range = motion_drivers::HOST_LATENCY_RANGE_MS;
        self.issue(
            value.span(),
            key,
            format!(
                "{ms} is out of range; allowed: {}..={} ms (how much later than on the wire an \
                 answer may reach the driver: the serial adapter and the I/O thread; default {})",
                range.start(),
                range.end(),
                motion_drivers::DEFAULT_HOST_LATENCY.as_millis()
            ),
        );
        None
    }

    /// What `allowed` pairs with the name `value` gives; otherwise an issue
    /// `unknown {what} "…"; allowed: {listed}` (`listed`: the names, and what each means).
    pub fn one_of<T: Copy>(
        &mut self,
        value: &Spanned<String>,
        key: &str,
        allowed: &[(&str, T)],
        what: &str,
        listed: &str,
    ) -> Option<T> {
        let name = value.get_ref().as_str();
        let found = allowed
            .iter()
            .find(|(allowed, _)| *allowed == name)
            .map(|&(_, found)| found);
        if found.is_none() {
            self.issue(
                value.span(),
                key,
                format!("unknown {what} {name:?}; allowed: {listed}"),
            );
        }
        found
    }
}

/// The board's keys of one table: what the server left after taking its general keys.
#[derive(Debug, Clone)]
pub struct KeyTable<'a> {
    table: Spanned<DeTable<'a>>,
}

impl<'a> KeyTable<'a> {
    /// The keys of `table` (spanned: its place in the file).
    #[must_use]
    pub fn new(table: Spanned<DeTable<'a>>) -> Self {
        Self { table }
    }

    /// No keys, at `span`.
    #[must_use]
    pub fn empty(span: Span) -> Self {
        Self::new(Spanned::new(span, DeTable::new()))
    }

    /// Where the table is in the file.
    #[must_use]
    pub fn span(&self) -> Span {
        self.table.span()
    }

    /// The keys set, in file order.
    pub fn keys(&self) -> impl Iterator<Item = (&str, Span)> + '_ {
        self.table
            .get_ref()
            .iter()
            .map(|(key, value)| (key.get_ref().as_ref(), value.span()))
    }

    /// The keys of the table under `key` (an axis's `home`), in file order; none when
    /// `key` is not set or not a table.
    pub fn keys_under(&self, key: &str) -> Vec<(&str, Span)> {
        self.table
            .get_ref()
            .iter()
            .filter(|(k, _)| k.get_ref().as_ref() == key)
            .filter_map(|(_, value)| match value.get_ref() {
                DeValue::Table(table) => Some(table),
                _ => None,
            })
            .flat_map(|table| {
                table
                    .iter()
                    .map(|(k, value)| (k.get_ref().as_ref(), value.span()))
            })
            .collect()
    }

    /// The same table without the keys `drop` says to drop (by name, at the top level).
    #[must_use]
    pub fn without(&self, drop: impl Fn(&str) -> bool) -> Self {
        let mut table = DeTable::new();
        for (key, value) in self.table.get_ref() {
            if !drop(key.get_ref().as_ref()) {
                table.insert(key.clone(), value.clone());
            }
        }
        Self::new(Spanned::new(self.table.span(), table))
    }

    /// Whether no key is set.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.table.get_ref().is_empty()
    }

    /// The table as the board's serde struct `T` (use `toml::Spanned` fields for values
    /// whose place an issue names, and `#[serde(deny_unknown_fields)]`). A value of the
    /// wrong type is reported through `issues` and gives `None`.
    pub fn parse<T: Deserialize<'a>>(&self, issues: &mut dyn KeyIssues) -> Option<T> {
        let value = Spanned::new(
            self.table.span(),
            DeValue::Table(self.table.get_ref().clone()),
        );
        match T::deserialize(toml::de::ValueDeserializer::from(value)) {
            Ok(parsed) => Some(parsed),
            Err(error) => {
                let span = error.span().unwrap_or_else(|| self.table.span());
                issues.report_refused(span, error.message());
                None
            }
        }
    }
}

/// The keys of a table as the board's serde struct `T` declares them (its fields, in
/// declaration order): what [`Board::device_key_names`](crate::Board::device_key_names)
/// and [`axis_key_names`](crate::Board::axis_key_names) return, so that a board writes
/// its key names once, in its struct. Empty for a `T` that is not a plain struct.
#[must_use]
pub fn key_names<'de, T: Deserialize<'de>>() -> &'static [&'static str] {
    match T::deserialize(FieldNames) {
        Err(Fields(fields)) => fields,
        Ok(_) => &[],
    }
}

/// A deserializer that answers nothing: it only asks the struct deserialized from it for
/// its field names ([`key_names`]), which it hands back as its error.
struct FieldNames;

/// The field names a struct's `Deserialize` named (none for anything else).
#[derive(Debug, thiserror::Error)]
#[error("not a struct")]
struct Fields(&'static [&'static str]);

impl serde::de::Error for Fields {
    fn custom<M: fmt::Display>(_: M) -> Self {
        Self(&[])
    }
}

impl<'de> serde::Deserializer<'de> for FieldNames {
    type Error = Fields;

    fn deserialize_any<V: serde::de::Visitor<'de>>(self, _: V) -> Result<V::Value, Fields> {
        Err(Fields(&[]))
    }

    fn deserialize_struct<V: serde::de::Visitor<'de>>(
        self,
        _: &'static str,
        fields: &'static [&'static str],
        _: V,
    ) -> Result<V::Value, Fields> {
        Err(Fields(fields))
    }

    serde::forward_to_deserialize_any! {
        bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string bytes byte_buf
        option unit unit_struct newtype_struct seq tuple tuple_struct map enum identifier
        ignored_any
    }
}

/// A [`KeyIssues`] that drops what it is told: for reading a table again whose issues were
/// reported already.
#[derive(Debug, Clone, Copy, Default)]
pub struct Quiet;

impl KeyIssues for Quiet {
    fn report_issue(&mut self, _: Span, _: &str, _: String) {}
    fn report_warning(&mut self, _: Span, _: &str, _: String) {}
    fn report_refused(&mut self, _: Span, _: &str) {}
}

impl<'a> KeyTable<'a> {
    /// [`parse`](Self::parse) with its issues dropped (they were reported when the board
    /// validated the table): for a cross-check that needs the spans again.
    pub fn parse_quiet<T: Deserialize<'a>>(&self) -> Option<T> {
        self.parse(&mut Quiet)
    }
}

/// Where a `[[device]]` table is, for naming its keys.
#[derive(Debug, Clone)]
pub struct DeviceContext {
    /// Index of the `[[device]]` table in the file.
    pub index: usize,
    /// The whole table.
    pub table: Span,
}

impl DeviceContext {
    /// `device[i].key`.
    #[must_use]
    pub fn key(&self, key: &str) -> String {
        format!("device[{}].{key}", self.index)
    }
}

/// Where an `[[axis]]` table is, and what a board needs of the axis's general keys to
/// convert its own (each `None` when that key was missing or invalid).
#[derive(Debug, Clone)]
pub struct AxisContext<'a> {
    /// Index of the `[[axis]]` table in the file.
    pub index: usize,
    /// The whole table.
    pub table: Span,
    /// The axis's `counts_per_unit`.
    pub counts_per_unit: Option<f64>,
    /// The axis's soft limit `min`.
    pub min: Option<f64>,
    /// The axis's soft limit `max`.
    pub max: Option<f64>,
    /// Where `max` was written.
    pub max_span: Option<Span>,
    /// The axis's unit.
    pub unit: Option<&'a str>,
    /// The channel it drives.
    pub channel: Option<usize>,
    /// The axis's `home.position` (the position it takes at the switch), and where it was
    /// written.
    pub home_position: Option<(f64, Span)>,
    /// The axis's `max_velocity`, units/s.
    pub max_velocity: Option<f64>,
    /// The axis's `max_accel`, units/s².
    pub max_accel: Option<f64>,
}

impl AxisContext<'_> {
    /// `axis[i].key`.
    #[must_use]
    pub fn key(&self, key: &str) -> String {
        format!("axis[{}].{key}", self.index)
    }
}

#[cfg(test)]
mod tests {
    use super::{Int, KeyIssues, Span, Spanned, key_names};

    /// Every issue told, as (span, key, message).
    #[derive(Default)]
    struct Told(Vec<(Span, String, String)>);

    impl KeyIssues for Told {
        fn report_issue(&mut self, span: Span, key: &str, message: String) {
            self.0.push((span, key.to_owned(), message));
        }
        fn report_warning(&mut self, _: Span, _: &str, _: String) {}
        fn report_refused(&mut self, _: Span, _: &str) {}
    }

    #[test]
    fn one_of_gives_the_named_value_or_names_what_is_allowed() {
        let allowed = [("low", false), ("high", true)];
        let mut told = Told::default();
        let issues: &mut dyn KeyIssues = &mut told;
        let high = Spanned::new(3..9, "high".to_owned());
        assert_eq!(
            issues.one_of(
                &high,
                "device[0].level",
                &allowed,
                "level",
                "\"low\", \"high\""
            ),
            Some(true)
        );
        let odd = Spanned::new(10..16, "middle".to_owned());
        assert_eq!(
            issues.one_of(
                &odd,
                "device[0].level",
                &allowed,
                "level",
                "\"low\", \"high\""
            ),
            None
        );
        assert_eq!(
            told.0,
            [(
                10..16,
                "device[0].level".to_owned(),
                "unknown level \"middle\"; allowed: \"low\", \"high\"".to_owned()
            )]
        );
    }

    #[test]
    fn key_names_are_the_fields_of_the_struct_in_order() {
        #[derive(serde::Deserialize)]
        #[serde(deny_unknown_fields)]
        #[allow(dead_code)]
        struct Raw {
            variant: Option<Spanned<String>>,
            switchover_ms: Option<Spanned<Int>>,
            rotary: Option<Spanned<bool>>,
        }
        assert_eq!(key_names::<Raw>(), ["variant", "switchover_ms", "rotary"]);
        assert!(key_names::<Int>().is_empty());
    }
}
