//! [`Contract::to_json`]: the contract as the C and Python layout checks read it.

use std::fmt::Write as _;

use super::{Contract, Enum, Struct};

/// `text` as a JSON string.
fn json_string(text: &str) -> String {
    let mut out = String::with_capacity(text.len() + 2);
    out.push('"');
    for c in text.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            c if (c as u32) < 0x20 => {
                let _ = write!(out, "\\u{:04x}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

impl Contract {
    /// The contract as one JSON object (stable key order): `constants` (name → value),
    /// `services` (leaf → name format), `layouts` (per payload: `rust`, `type_name`,
    /// `size`, `align`, `fields` with `name`, `offset`, `size`, `type`) and `enums` (per
    /// enumeration or flag set: `rust`, `repr`, `flags`, `variants` with `name`, `value`,
    /// `text`).
    pub fn to_json(&self) -> String {
        let constants: Vec<String> = self
            .constants
            .iter()
            .map(|constant| format!("\n    {}: {}", json_string(constant.name), constant.value))
            .collect();
        let services: Vec<String> = self
            .services
            .iter()
            .map(|service| {
                let (leaf, format) = (json_string(service.leaf), json_string(&service.format));
                format!("\n    {leaf}: {format}")
            })
            .collect();
        let layouts: Vec<String> = self.structs.iter().map(|s| struct_json(s)).collect();
        let enums: Vec<String> = self.enums.iter().map(enum_json).collect();
        format!(
            "{{\n  \"constants\": {{{}\n  }},\n  \"services\": {{{}\n  }},\n  \"layouts\": \
             [{}\n  ],\n  \"enums\": [{}\n  ]\n}}\n",
            constants.join(","),
            services.join(","),
            layouts.join(","),
            enums.join(",")
        )
    }
}

fn struct_json(payload: &Struct) -> String {
    let fields: Vec<String> = payload
        .fields
        .iter()
        .map(|field| {
            format!(
                "\n        {{\"name\": {}, \"offset\": {}, \"size\": {}, \"type\": {}}}",
                json_string(field.name),
                field.offset,
                field.size,
                json_string(&field.ty.spelling())
            )
        })
        .collect();
    format!(
        "\n    {{\n      \"rust\": {},\n      \"type_name\": {},\n      \"size\": {},\n      \
         \"align\": {},\n      \"fields\": [{}\n      ]\n    }}",
        json_string(payload.name),
        json_string(payload.type_name),
        payload.size,
        payload.align,
        fields.join(",")
    )
}

fn enum_json(item: &Enum) -> String {
    let variants: Vec<String> = item
        .variants
        .iter()
        .map(|variant| {
            let text = variant.text.map_or_else(|| "null".to_owned(), json_string);
            format!(
                "\n        {{\"name\": {}, \"value\": {}, \"text\": {text}}}",
                json_string(&variant.name),
                variant.value
            )
        })
        .collect();
    format!(
        "\n    {{\n      \"rust\": {},\n      \"repr\": {},\n      \"flags\": {},\n      \
         \"variants\": [{}\n      ]\n    }}",
        json_string(item.name),
        json_string(item.repr.name()),
        item.flags,
        variants.join(",")
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strings_are_escaped() {
        assert_eq!(json_string("a\"b\\c\nd\u{1}"), r#""a\"b\\c\nd\u0001""#);
    }

    #[test]
    fn the_contract_has_every_section() {
        let json = super::super::contract().to_json();
        for key in ["\"constants\"", "\"services\"", "\"layouts\"", "\"enums\""] {
            assert!(json.contains(key), "{key} missing");
        }
        assert!(json.contains("\"rust\": \"MotionFrame\""));
        assert!(json.contains(
            "{\"name\": \"values\", \"offset\": 40, \"size\": 24, \"type\": \"f64[3]\"}"
        ));
    }
}
