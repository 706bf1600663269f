//! [`Contract::c_header`]: `include/motiond.h`, the C11 / C++ mirror of the contract.
//!
//! Every layout fact (struct, field, type, offset, size, alignment, constant, enumeration
//! value and text, type name, service name) comes from the description; the prose at the
//! top and the two helper functions at the bottom are fixed text.

use std::fmt::Write as _;

use super::docs::{rename_code, snake, text, upper_snake, wrap};
use super::{Contract, Enum, Field, Scalar, Struct, Type};

/// Columns of the generated header's comments.
const WIDTH: usize = 96;
/// Columns a field with its doc on the same line may take.
const FIELD_LINE: usize = 100;

const PREAMBLE: &str = "\
/*
 * motiond.h - the shared-memory contract of motiond for C (C11) and C++ clients.
 *
 * GENERATED from the Rust description of the contract (crate motion-ipc, src/schema) by
 * `cargo run -p motion-ipc --example gen` (or scripts/gen): do not edit; change the Rust
 * payload and run the generator. crates/motion-ipc/tests/generated.rs fails while this
 * file differs from what the generator writes, and crates/motion-ipc/tests/c_header.rs
 * compiles a probe against it and compares every size, alignment, offset, field type,
 * constant, enum value, text and type name with the Rust definitions.
 *
 * motiond publishes its state and takes commands over iceoryx2 services. Every payload
 * is a fixed-size #[repr(C)] Rust struct; this header mirrors each one field by field, in
 * memory order, with the iceoryx2 type name a port must announce (iceoryx2 only connects
 * ports whose payload type name, size and alignment match the server's). Open the
 * services, never create them; user header: none (iceoryx2's \"()\", size 0, alignment 1).
 * Enumerations travel as the plain integer fields named in each struct; compare them with
 * the MOTIOND_* constants below. Text fields are UTF-8, zero padded (not necessarily zero
 * terminated when full).
 *
 * examples/c/ holds a complete program (frames in, a command out) on iceoryx2's C API.
 *
 * Services of the instance NAME ([server] name in the server's config):
 *
";

const PROLOGUE: &str = "\
#ifndef MOTIOND_H
#define MOTIOND_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
#define MOTIOND_STATIC_ASSERT(cond, msg) static_assert(cond, msg)
#define MOTIOND_ALIGNOF(type) alignof(type)
extern \"C\" {
#else
#define MOTIOND_STATIC_ASSERT(cond, msg) _Static_assert(cond, msg)
#define MOTIOND_ALIGNOF(type) _Alignof(type)
#endif
";

const HELPERS: &str = "\
/* --- helpers ------------------------------------------------------------------------------ */

/** A client id from an iceoryx2 node id given as its two 64-bit halves. */
static inline motiond_client_id_t motiond_client_id(uint64_t lo, uint64_t hi) {
    motiond_client_id_t id;
    id.lo = lo;
    id.hi = hi;
    return id;
}

/** A request of this schema: kind on axis (or signal) index, values zero. */
static inline motiond_command_request_t motiond_command_request(
    uint32_t kind, uint32_t axis, uint64_t sequence) {
    motiond_command_request_t request;
    request.schema_version = MOTIOND_SCHEMA_VERSION;
    request.kind = kind;
    request.client = motiond_client_id(0, 0);
    request.sequence = sequence;
    request.axis = axis;
    request.target = MOTIOND_TARGET_AXIS;
    request.values[0] = 0.0;
    request.values[1] = 0.0;
    request.values[2] = 0.0;
    return request;
}

#ifdef __cplusplus
} /* extern \"C\" */
#endif

#endif /* MOTIOND_H */
";

/// The header's type of a payload: `motiond_motion_frame_t` for `MotionFrame`.
pub fn c_struct(name: &str) -> String {
    format!("motiond_{}_t", snake(name))
}

/// The C name of an enumeration value or flag bit (`MOTIOND_REASON_OUT_OF_RANGE`,
/// `MOTIOND_AXIS_FLAGS_MOVING`).
pub fn c_enum_value(item: &Enum, variant: &str) -> String {
    if item.flags {
        format!("MOTIOND_{}_{variant}", upper_snake(item.name))
    } else {
        format!(
            "MOTIOND_{}_{}",
            upper_snake(item.name),
            upper_snake(variant)
        )
    }
}

fn c_scalar(scalar: Scalar) -> &'static str {
    match scalar {
        Scalar::U8 => "uint8_t",
        Scalar::U16 => "uint16_t",
        Scalar::U32 => "uint32_t",
        Scalar::U64 => "uint64_t",
        Scalar::I64 => "int64_t",
        Scalar::F64 => "double",
    }
}

/// `uint8_t name[MOTIOND_NAME_LEN]` for a field.
fn c_declaration(ty: &Type, name: &str) -> String {
    match ty {
        Type::Scalar(scalar) => format!("{} {name}", c_scalar(*scalar)),
        Type::Struct { schema } => format!("{} {name}", c_struct(schema.name)),
        Type::Array {
            element,
            len,
            len_name,
        } => {
            let len = len_name.map_or_else(|| len.to_string(), |c| format!("MOTIOND_{c}"));
            c_declaration(element, &format!("{name}[{len}]"))
        }
    }
}

/// A `/** … */` comment at `indent` spaces: one line when it fits, else a block.
fn comment(out: &mut String, indent: usize, prose: &str) {
    let pad = " ".repeat(indent);
    let paragraphs = wrap(prose, WIDTH - indent - 3);
    if let [only] = paragraphs.as_slice()
        && let [line] = only.as_slice()
        && indent + line.chars().count() + 7 <= WIDTH
    {
        let _ = writeln!(out, "{pad}/** {line} */");
        return;
    }
    let _ = writeln!(out, "{pad}/**");
    for (index, paragraph) in paragraphs.iter().enumerate() {
        if index > 0 {
            let _ = writeln!(out, "{pad} *");
        }
        for line in paragraph {
            let _ = writeln!(out, "{pad} * {line}");
        }
    }
    let _ = writeln!(out, "{pad} */");
}

impl Contract {
    /// `include/motiond.h`.
    pub fn c_header(&self) -> String {
        let mut out = String::from(PREAMBLE);
        for service in &self.services {
            let macro_name = format!("MOTIOND_SERVICE_{}", service.leaf.to_ascii_uppercase());
            let doc = self.c_prose(service.doc);
            for (index, line) in wrap(&doc, WIDTH - 37).concat().iter().enumerate() {
                let head = if index == 0 { macro_name.as_str() } else { "" };
                let _ = writeln!(out, " *   {head:<29}   {line}");
            }
        }
        out.push_str(" */\n");
        out.push_str(PROLOGUE);
        self.c_constants(&mut out);
        self.c_enums(&mut out);
        out.push_str("\n/* --- payloads ----------------------------------------------------------------------------- */\n");
        for payload in &self.structs {
            self.c_payload(&mut out, payload);
        }
        self.c_texts(&mut out);
        out.push('\n');
        out.push_str(HELPERS);
        out
    }

    /// Doc prose with the contract's Rust names turned into the header's.
    fn c_prose(&self, prose: &str) -> String {
        rename_code(prose, |code| self.c_name(code))
    }

    /// The header's name for a code span of the docs: payloads, enumerations, constants
    /// and `Payload.field` by their C names; anything else stays a code span.
    fn c_name(&self, code: &str) -> String {
        let (head, tail) = code
            .split_once("::")
            .or_else(|| code.split_once('.'))
            .unwrap_or((code, ""));
        let suffix = if tail.is_empty() {
            String::new()
        } else {
            format!(".{tail}")
        };
        if self.structs.iter().any(|s| s.name == head) {
            format!("{}{suffix}", c_struct(head))
        } else if tail.is_empty() && self.enums.iter().any(|e| e.name == code) {
            format!("MOTIOND_{}_*", upper_snake(code))
        } else if tail.is_empty() && self.constant(code).is_some() {
            format!("MOTIOND_{code}")
        } else {
            format!("`{code}`")
        }
    }

    fn c_constants(&self, out: &mut String) {
        out.push_str("\n/* --- constants ---------------------------------------------------------------------------- */\n\n");
        for constant in &self.constants {
            comment(out, 0, &self.c_prose(constant.doc));
            let _ = writeln!(out, "#define MOTIOND_{} {}u", constant.name, constant.value);
        }
        out.push_str("\n/* Service names: printf formats taking the instance name. */\n");
        for service in &self.services {
            let leaf = service.leaf.to_ascii_uppercase();
            let _ = writeln!(out, "#define MOTIOND_SERVICE_{leaf} \"{}\"", service.format);
        }
        out.push_str("\n/* iceoryx2 type names of the payloads. */\n");
        for payload in &self.structs {
            let name = upper_snake(payload.name);
            let _ = writeln!(
                out,
                "#define MOTIOND_TYPE_NAME_{name} \"{}\"",
                payload.type_name
            );
        }
    }

    fn c_enums(&self, out: &mut String) {
        out.push_str("\n/* --- enumerations (values of the integer fields) ------------------------------------------ */\n");
        for item in &self.enums {
            out.push('\n');
            comment(out, 0, &self.c_prose(item.doc));
            let _ = writeln!(out, "enum motiond_{} {{", snake(item.name));
            let values: Vec<String> = item
                .variants
                .iter()
                .map(|variant| {
                    let value = if item.flags && variant.value.is_power_of_two() {
                        format!("1 << {}", variant.value.trailing_zeros())
                    } else {
                        variant.value.to_string()
                    };
                    format!("    {} = {value}", c_enum_value(item, &variant.name))
                })
                .collect();
            out.push_str(&values.join(",\n"));
            out.push_str("\n};\n");
        }
    }

    fn c_payload(&self, out: &mut String, payload: &Struct) {
        let ty = c_struct(payload.name);
        let layout = format!(
            "{} bytes, alignment {}; iceoryx2 type name \"{}\".",
            payload.size, payload.align, payload.type_name
        );
        out.push('\n');
        comment(
            out,
            0,
            &format!("{}\n\n{layout}", self.c_prose(&text(payload.docs))),
        );
        let _ = writeln!(out, "typedef struct motiond_{} {{", snake(payload.name));
        for field in payload.fields {
            self.c_field(out, field);
        }
        let _ = writeln!(out, "}} {ty};");
        let _ = writeln!(
            out,
            "MOTIOND_STATIC_ASSERT(sizeof({ty}) == {}, \"{ty} size\");",
            payload.size
        );
        let _ = writeln!(
            out,
            "MOTIOND_STATIC_ASSERT(MOTIOND_ALIGNOF({ty}) == {}, \"{ty} alignment\");",
            payload.align
        );
    }

    /// A field: `type name; /**< doc (offset N) */` when that fits on a line, else the doc
    /// above it.
    fn c_field(&self, out: &mut String, field: &Field) {
        let declaration = format!("{};", c_declaration(&field.ty, field.name));
        let doc = self.c_prose(&text(field.docs));
        let offset = format!("offset {}", field.offset);
        let line = format!(
            "    {declaration} /**< {} ({offset}) */",
            doc.replace('\n', " ")
        );
        if !doc.contains("\n\n") && line.chars().count() <= FIELD_LINE {
            let _ = writeln!(out, "{line}");
        } else {
            comment(out, 4, &doc);
            let _ = writeln!(out, "    {declaration} /* {offset} */");
        }
    }

    fn c_texts(&self, out: &mut String) {
        out.push_str("\n/* --- texts -------------------------------------------------------------------------------- */\n");
        for item in &self.enums {
            if item.variants.iter().all(|variant| variant.text.is_none()) {
                continue;
            }
            out.push('\n');
            comment(
                out,
                0,
                &format!(
                    "The text of a MOTIOND_{}_* value; NULL for a value unknown here.",
                    upper_snake(item.name)
                ),
            );
            let _ = writeln!(
                out,
                "static inline const char *motiond_{}_text(uint32_t value) {{\n    switch (value) {{",
                snake(item.name)
            );
            for variant in &item.variants {
                if let Some(text) = variant.text {
                    let text = text.replace('\\', "\\\\").replace('"', "\\\"");
                    let value = c_enum_value(item, &variant.name);
                    let _ = writeln!(out, "    case {value}: return \"{text}\";");
                }
            }
            out.push_str("    default: return NULL;\n    }\n}\n");
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn declarations_name_array_lengths_by_their_constants() {
        let text = Type::Array {
            element: &Type::Scalar(Scalar::U8),
            len: 32,
            len_name: Some("NAME_LEN"),
        };
        assert_eq!(
            c_declaration(&text, "name"),
            "uint8_t name[MOTIOND_NAME_LEN]"
        );
        let values = Type::Array {
            element: &Type::Scalar(Scalar::F64),
            len: 3,
            len_name: None,
        };
        assert_eq!(c_declaration(&values, "values"), "double values[3]");
    }

    #[test]
    fn comments_fit_on_one_line_or_become_blocks() {
        let mut one = String::new();
        comment(&mut one, 4, "Short.");
        assert_eq!(one, "    /** Short. */\n");
        let mut block = String::new();
        comment(&mut block, 0, &"word ".repeat(40));
        assert!(block.starts_with("/**\n * word"), "{block}");
        assert!(
            block.lines().all(|line| line.chars().count() <= WIDTH),
            "{block}"
        );
    }

    #[test]
    fn docs_use_the_headers_names() {
        let contract = super::super::contract();
        let prose = contract.c_prose("`AxisFlags` bits of `AxisState.flags`, `MAX_AXES`, `x`");
        assert_eq!(
            prose,
            "MOTIOND_AXIS_FLAGS_* bits of motiond_axis_state_t.flags, MOTIOND_MAX_AXES, `x`"
        );
    }
}
