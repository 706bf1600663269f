//! [`Contract::python_module`]: `python/src/motiond/_layout.py`, the ctypes mirrors of the
//! contract that `motiond.ipc` re-exports.
//!
//! Every layout fact comes from the description; the base classes and the few hand-written
//! methods live in `python/src/motiond/_mirror_base.py`.

use std::fmt::Write as _;

use super::docs::{rename_code, text, upper_snake, wrap};
use super::{Contract, Enum, Scalar, Struct, Type};

/// Columns of the generated module.
const WIDTH: usize = 100;

/// Mirrors that carry hand-written methods: the mixin of `_mirror_base.py` each inherits.
const METHODS: &[(&str, &str)] = &[
    ("ClientId", "ClientIdMethods"),
    ("AxisInfo", "AxisInfoMethods"),
    ("DeviceInfo", "DeviceInfoMethods"),
    ("Reason", "ReasonMethods"),
];

const HEADER: &str = "\
\"\"\"The shared-memory contract of motiond as ctypes mirrors, enumerations and constants.

GENERATED from the Rust description of the contract (crate motion-ipc, src/schema) by
``cargo run -p motion-ipc --example gen`` (or ``scripts/gen``): do not edit; change the Rust
payload and run the generator. Import these names from :mod:`motiond.ipc`.
\"\"\"

from __future__ import annotations

import ctypes
import enum
from typing import Dict, Type

from ._mirror_base import (
    AxisInfoMethods,
    ClientIdMethods,
    DeviceInfoMethods,
    Payload,
    ReasonMethods,
    TextedEnum,
)
";

fn py_scalar(scalar: Scalar) -> &'static str {
    match scalar {
        Scalar::U8 => "ctypes.c_uint8",
        Scalar::U16 => "ctypes.c_uint16",
        Scalar::U32 => "ctypes.c_uint32",
        Scalar::U64 => "ctypes.c_uint64",
        Scalar::I64 => "ctypes.c_int64",
        Scalar::F64 => "ctypes.c_double",
    }
}

/// The ctypes type of a field: `ctypes.c_uint8 * NAME_LEN`, `AxisState * MAX_AXES`.
fn py_type(ty: &Type) -> String {
    match ty {
        Type::Scalar(scalar) => py_scalar(*scalar).to_owned(),
        Type::Struct { schema } => schema.name.to_owned(),
        Type::Array {
            element,
            len,
            len_name,
        } => {
            let len = len_name.map_or_else(|| len.to_string(), str::to_owned);
            format!("{} * {len}", py_type(element))
        }
    }
}

/// `text` as a Python string literal.
fn py_string(text: &str) -> String {
    format!("\"{}\"", text.replace('\\', "\\\\").replace('"', "\\\""))
}

/// Doc prose in reStructuredText: code spans doubled.
fn rst(prose: &str) -> String {
    rename_code(prose, |code| format!("``{}``", code.replace("::", ".")))
}

/// A docstring at `indent` spaces.
fn docstring(out: &mut String, indent: usize, prose: &str) {
    let pad = " ".repeat(indent);
    let prose = prose.replace('\\', "\\\\");
    let paragraphs = wrap(&prose, WIDTH - indent - 3);
    let body: Vec<String> = paragraphs
        .iter()
        .map(|lines| lines.join(&format!("\n{pad}")))
        .collect();
    let _ = writeln!(out, "{pad}\"\"\"{}\"\"\"", body.join(&format!("\n\n{pad}")));
}

/// Comment lines starting with `marker` (`#`, or `#:` for a documented name) at `indent`
/// spaces.
fn comment(out: &mut String, indent: usize, marker: &str, prose: &str) {
    let pad = " ".repeat(indent);
    for paragraph in wrap(prose, WIDTH - indent - marker.len() - 1) {
        for line in paragraph {
            let _ = writeln!(out, "{pad}{marker} {line}");
        }
    }
}

fn mixin(name: &str) -> Option<&'static str> {
    METHODS
        .iter()
        .find(|(mirror, _)| *mirror == name)
        .map(|(_, methods)| *methods)
}

impl Contract {
    /// `python/src/motiond/_layout.py`.
    pub fn python_module(&self) -> String {
        let mut out = String::from(HEADER);
        out.push_str("\n# --- constants ---------------------------------------------------------------------------\n\n");
        for constant in &self.constants {
            comment(&mut out, 0, "#:", &rst(constant.doc));
            let _ = writeln!(out, "{} = {}", constant.name, constant.value);
        }
        out.push_str("\n#: Service name formats of one instance; ``%s`` is the instance name.\n");
        out.push_str("SERVICES: Dict[str, str] = {\n");
        for service in &self.services {
            let _ = writeln!(
                out,
                "    {}: {},",
                py_string(service.leaf),
                py_string(&service.format)
            );
        }
        out.push_str("}\n");
        out.push_str("\n# --- payloads ----------------------------------------------------------------------------\n");
        for payload in &self.structs {
            py_payload(&mut out, payload);
        }
        let payloads: Vec<&str> = self.structs.iter().map(|s| s.name).collect();
        py_registry(
            &mut out,
            "PAYLOADS: Dict[str, Type[Payload]]",
            "payload mirror",
            &payloads,
        );
        out.push_str("\n# --- enumerations ------------------------------------------------------------------------\n");
        for item in &self.enums {
            py_enum(&mut out, item);
        }
        let enums: Vec<&str> = self.enums.iter().map(|e| e.name).collect();
        py_registry(
            &mut out,
            "ENUMS: Dict[str, type]",
            "enumeration and flag set",
            &enums,
        );
        out
    }
}

/// `declaration = {"Name": Name, …}`: every class of a kind by its Rust type name.
fn py_registry(out: &mut String, declaration: &str, what: &str, names: &[&str]) {
    let _ = writeln!(
        out,
        "\n\n#: Every {what}, by Rust type name.\n{declaration} = {{"
    );
    for name in names {
        let _ = writeln!(out, "    {}: {name},", py_string(name));
    }
    out.push_str("}\n");
}

fn py_payload(out: &mut String, payload: &Struct) {
    let bases = match mixin(payload.name) {
        Some(methods) => format!("{methods}, Payload"),
        None => "Payload".to_owned(),
    };
    let _ = writeln!(out, "\n\nclass {}({bases}):", payload.name);
    let layout = format!("{} bytes, alignment {}.", payload.size, payload.align);
    docstring(out, 4, &format!("{}\n\n{layout}", rst(&text(payload.docs))));
    let _ = writeln!(out, "\n    _type_name_ = {}", py_string(payload.type_name));
    out.push_str("    _fields_ = [\n");
    for field in payload.fields {
        let entry = format!("({}, {}),", py_string(field.name), py_type(&field.ty));
        let doc = rst(&text(field.docs));
        if !doc.contains("\n\n") && 8 + entry.len() + 4 + doc.chars().count() <= WIDTH {
            let doc = doc.replace('\n', " ");
            let _ = writeln!(out, "        {entry}  # {doc}");
        } else {
            comment(out, 8, "#", &doc);
            let _ = writeln!(out, "        {entry}");
        }
    }
    out.push_str("    ]\n");
}

fn py_enum(out: &mut String, item: &Enum) {
    let bases = match (item.flags, mixin(item.name)) {
        (true, _) => "enum.IntFlag".to_owned(),
        (false, Some(methods)) => format!("{methods}, TextedEnum"),
        (false, None) => "TextedEnum".to_owned(),
    };
    let _ = writeln!(out, "\n\nclass {}({bases}):", item.name);
    docstring(out, 4, &rst(item.doc));
    out.push('\n');
    for variant in &item.variants {
        let name = if item.flags {
            variant.name.clone()
        } else {
            upper_snake(&variant.name)
        };
        let value = if item.flags && variant.value.is_power_of_two() {
            format!("1 << {}", variant.value.trailing_zeros())
        } else {
            variant.value.to_string()
        };
        match variant.text.map(py_string) {
            Some(text) if name.len() + value.len() + text.len() + 9 <= WIDTH => {
                let _ = writeln!(out, "    {name} = {value}, {text}");
            }
            Some(text) => {
                let _ = writeln!(
                    out,
                    "    {name} = (\n        {value},\n        {text},\n    )"
                );
            }
            None => {
                let _ = writeln!(out, "    {name} = {value}");
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn field_types_are_ctypes() {
        let name = Type::Array {
            element: &Type::Scalar(Scalar::U8),
            len: 32,
            len_name: Some("NAME_LEN"),
        };
        assert_eq!(py_type(&name), "ctypes.c_uint8 * NAME_LEN");
        assert_eq!(py_type(&Type::Scalar(Scalar::F64)), "ctypes.c_double");
    }

    #[test]
    fn strings_and_docstrings_are_escaped() {
        assert_eq!(py_string("a \"b\" \\"), r#""a \"b\" \\""#);
        let mut out = String::new();
        docstring(&mut out, 4, "one `x`\\y\n\ntwo");
        assert_eq!(out, "    \"\"\"one `x`\\\\y\n\n    two\"\"\"\n");
    }

    #[test]
    fn mixins_name_mirrors_of_the_contract() {
        let contract = super::super::contract();
        for (mirror, _) in METHODS {
            let known = contract.structs.iter().any(|s| s.name == *mirror)
                || contract.enums.iter().any(|e| e.name == *mirror);
            assert!(known, "{mirror} is not in the contract");
        }
    }
}
