//! Reading YAML: serde-saphyr with the spec's safety options, its errors located and, for a
//! user, diagnosed ([`super::syntax`]).
//!
//! A load reads the text twice: once for its top-level keys only ([`top_level_keys`], which
//! decides the [`super::kind`]; values are skipped, not built), then into that kind's raw
//! structs. One parse is not practical with serde-saphyr 1.3: it has no public way to keep a
//! parsed document with its locations and deserialize it later (its event replay is
//! crate-private; a serde-buffered value, as an untagged enum uses, loses the locations that
//! [`Spanned`] needs, and turns a precise error into "did not match any variant"). Parsing
//! straight into a combined type instead would have to type a value before the keys after it
//! are seen, so a spec that mixes the kinds, or misspells a top-level key, would get a type
//! error in place of the kind's message. (A spec with an error is parsed more times still:
//! probed copies find what the field allows.)

use std::borrow::Cow;
use std::collections::BTreeMap;

use serde::de::IgnoredAny;
use serde::{Deserialize, Deserializer};
use serde_saphyr::Location;

use super::error::{SpecError, SpecErrors};
use super::syntax;

/// A value with where the spec gives it: serde-saphyr's `Spanned`, which it deserializes
/// through (so locations and messages are serde-saphyr's), in a type of the baker's own so that
/// it can describe itself in a JSON Schema ([`super::schema`]): as its value, the location
/// being no part of what a user writes.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Spanned<T> {
    pub value: T,
    pub referenced: Location,
    pub defined: Location,
}

impl<T> Spanned<T> {
    pub const fn new(value: T, referenced: Location, defined: Location) -> Self {
        Spanned {
            value,
            referenced,
            defined,
        }
    }
}

impl<'de, T: Deserialize<'de>> Deserialize<'de> for Spanned<T> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        serde_saphyr::Spanned::<T>::deserialize(d)
            .map(|s| Spanned::new(s.value, s.referenced, s.defined))
    }
}

/// The schema of the value alone (same name and id, so a spanned struct is one definition).
impl<T: schemars::JsonSchema> schemars::JsonSchema for Spanned<T> {
    fn inline_schema() -> bool {
        T::inline_schema()
    }
    fn schema_name() -> Cow<'static, str> {
        T::schema_name()
    }
    fn schema_id() -> Cow<'static, str> {
        T::schema_id()
    }
    fn json_schema(g: &mut schemars::SchemaGenerator) -> schemars::Schema {
        T::json_schema(g)
    }
}

/// How specs are parsed: serde-saphyr's budgets (nodes, aliases, depth: an alias bomb or a
/// deeply nested document is an error, not an exhausted machine), and explicit tags it does
/// not know (`!!python/object`) rejected rather than ignored.
pub(super) fn options() -> serde_saphyr::Options {
    serde_saphyr::options! {
        reject_unsupported_tags: true,
    }
}

/// The keys of the top-level map of `text` (in sorted order), its values skipped.
pub(super) fn top_level_keys(text: &str) -> Result<Vec<String>, serde_saphyr::Error> {
    serde_saphyr::from_str_with_options::<BTreeMap<String, IgnoredAny>>(text, options())
        .map(|map| map.into_keys().collect())
}

/// Parses spec text into its raw serde form. A syntax or type error names file:line:column,
/// the field and, where it can be found, what the field allows ([`syntax::diagnose`]);
/// `check` validates probed copies of the text for that.
pub(super) fn parse<T: serde::de::DeserializeOwned>(
    file: &str,
    text: &str,
    check: syntax::Check,
) -> Result<T, SpecErrors> {
    parse_plain(file, text).map_err(|e| {
        let SpecError::Syntax {
            line,
            column,
            message,
            ..
        } = e
        else {
            return SpecErrors(vec![e]);
        };
        let d = syntax::diagnose(text, line, column, &message, check);
        SpecErrors(vec![SpecError::Syntax {
            file: file.to_string(),
            line: d.line,
            column: d.column,
            message: d.message,
        }])
    })
}

/// serde-saphyr's error as it comes, at its line and column.
pub(super) fn parse_plain<T: serde::de::DeserializeOwned>(
    file: &str,
    text: &str,
) -> Result<T, SpecError> {
    serde_saphyr::from_str_with_options(text, options()).map_err(|e| {
        let (line, column) = e
            .location()
            .map(|l| (l.line(), l.column()))
            .unwrap_or((0, 0));
        SpecError::Syntax {
            file: file.to_string(),
            line,
            column,
            message: e.to_string(),
        }
    })
}
