//! Checks `include/motiond.h` against this crate: compiles a C11 probe against the header
//! with the system C compiler and compares what it prints with the Rust definitions.
//!
//! The probe is generated from the contract's description (`motion_ipc::schema`), the same
//! one the header itself is generated from: it checks what the C compiler makes of the
//! generated text.
//! for every payload it prints `sizeof`, `_Alignof` and the iceoryx2 type name macro, and
//! for every Rust field the C field of the same name: `offsetof`, `sizeof` and its type
//! (told by `_Generic`; arrays by element type and count); for every enumeration value,
//! flag bit, constant and service name the header's macro or enum constant; for every
//! text the header's `motiond_<enum>_text` function. A field, value or text the header
//! lacks fails the compile (the test shows the compiler's message); a different value
//! fails the comparison (the test lists every difference). The header is also compiled as
//! C++ so that C++ clients can include it.
//!
//! Naming: payload `MotionFrame` → `motiond_motion_frame_t` and
//! `MOTIOND_TYPE_NAME_MOTION_FRAME`; enum value `Reason::OutOfRange` →
//! `MOTIOND_REASON_OUT_OF_RANGE`; flag `AxisFlags::MOVING` → `MOTIOND_AXIS_FLAGS_MOVING`;
//! constant `MAX_AXES` → `MOTIOND_MAX_AXES`; service `frame` → `MOTIOND_SERVICE_FRAME`.

use std::collections::BTreeSet;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;

use motion_ipc::schema::{Contract, c_enum_value, c_struct, contract, snake};

/// `OutOfRange` → `OUT_OF_RANGE`.
fn upper(name: &str) -> String {
    snake(name).to_ascii_uppercase()
}

/// Whether the Rust field type is an array (`u8[32]`).
fn is_array(ty: &str) -> bool {
    ty.ends_with(']')
}

/// The lines the probe must print, from the Rust side.
fn expected(contract: &Contract) -> BTreeSet<String> {
    let mut lines = BTreeSet::new();
    for layout in &contract.structs {
        let name = layout.name;
        lines.insert(format!("layout {name} size {}", layout.size));
        lines.insert(format!("layout {name} align {}", layout.align));
        lines.insert(format!("layout {name} type_name {}", layout.type_name));
        for field in layout.fields {
            lines.insert(format!(
                "field {name} {} {} {} {}",
                field.name,
                field.offset,
                field.size,
                field.ty.spelling()
            ));
        }
    }
    for item in &contract.enums {
        for variant in &item.variants {
            lines.insert(format!(
                "enum {} {} {}",
                item.name, variant.name, variant.value
            ));
            if let Some(text) = variant.text {
                lines.insert(format!("text {} {} {text}", item.name, variant.name));
            }
        }
    }
    for constant in &contract.constants {
        lines.insert(format!("const {} {}", constant.name, constant.value));
    }
    for service in &contract.services {
        lines.insert(format!("service {} {}", service.leaf, service.format));
    }
    lines
}

/// A C program printing, from the header, what `expected` lists.
fn probe_source(contract: &Contract) -> String {
    let mut c = String::from(
        "#include <stddef.h>\n#include <stdint.h>\n#include <stdio.h>\n#include \"motiond.h\"\n\n",
    );
    c.push_str(
        "#define TY(x) _Generic((x), uint8_t: \"u8\", uint16_t: \"u16\", uint32_t: \"u32\", \\\n",
    );
    c.push_str("    uint64_t: \"u64\", int64_t: \"i64\", double: \"f64\", \\\n");
    for layout in &contract.structs {
        let _ = writeln!(c, "    {}: \"{}\", \\", c_struct(layout.name), layout.name);
    }
    c.push_str("    default: \"?\")\n\n");
    c.push_str(
        "static const char *or_null(const char *text) { return text ? text : \"(null)\"; }\n\n",
    );
    c.push_str("int main(void) {\n");
    for layout in &contract.structs {
        let name = layout.name;
        let ty = c_struct(name);
        let _ = writeln!(c, "    {{\n        const {ty} *v = NULL;\n        (void)v;");
        let _ = writeln!(
            c,
            "        printf(\"layout {name} size %zu\\n\", sizeof({ty}));\n        \
             printf(\"layout {name} align %zu\\n\", (size_t)_Alignof({ty}));\n        \
             printf(\"layout {name} type_name %s\\n\", MOTIOND_TYPE_NAME_{});",
            upper(name)
        );
        for field in layout.fields {
            let f = field.name;
            if is_array(&field.ty.spelling()) {
                let _ = writeln!(
                    c,
                    "        printf(\"field {name} {f} %zu %zu %s[%zu]\\n\", offsetof({ty}, {f}), \
                     sizeof(v->{f}), TY(v->{f}[0]), sizeof(v->{f}) / sizeof(v->{f}[0]));"
                );
            } else {
                let _ = writeln!(
                    c,
                    "        printf(\"field {name} {f} %zu %zu %s\\n\", offsetof({ty}, {f}), \
                     sizeof(v->{f}), TY(v->{f}));"
                );
            }
        }
        c.push_str("    }\n");
    }
    for item in &contract.enums {
        for variant in &item.variants {
            let constant = c_enum_value(item, &variant.name);
            let _ = writeln!(
                c,
                "    printf(\"enum {} {} %lld\\n\", (long long){constant});",
                item.name, variant.name
            );
            if variant.text.is_some() {
                let _ = writeln!(
                    c,
                    "    printf(\"text {} {} %s\\n\", or_null(motiond_{}_text({constant})));",
                    item.name,
                    variant.name,
                    snake(item.name)
                );
            }
        }
    }
    for constant in &contract.constants {
        let name = constant.name;
        let _ = writeln!(
            c,
            "    printf(\"const {name} %llu\\n\", (unsigned long long)MOTIOND_{name});"
        );
    }
    for service in &contract.services {
        let _ = writeln!(
            c,
            "    printf(\"service {} %s\\n\", MOTIOND_SERVICE_{});",
            service.leaf,
            service.leaf.to_ascii_uppercase()
        );
    }
    c.push_str("    return 0;\n}\n");
    c
}

fn include_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../include")
}

fn work_dir() -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("motiond-c-header");
    std::fs::create_dir_all(&dir).expect("create the probe's directory");
    dir
}

/// Runs `command`, failing the test with its output when it fails.
fn run(mut command: Command, what: &str) -> String {
    let output = command
        .output()
        .unwrap_or_else(|error| panic!("could not run {what} ({command:?}): {error}; a C and C++ compiler (gcc) is needed, or set CC / CXX"));
    assert!(
        output.status.success(),
        "{what} failed ({command:?}):\n{}{}",
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    );
    String::from_utf8_lossy(&output.stdout).into_owned()
}

#[test]
fn c_header_matches_the_rust_layout() {
    let contract = contract();
    let dir = work_dir();
    let source = dir.join("probe.c");
    std::fs::write(&source, probe_source(&contract)).expect("write the probe");
    let binary = dir.join("probe");
    let cc = std::env::var("CC").unwrap_or_else(|_| "cc".to_owned());
    let mut compile = Command::new(&cc);
    compile
        .args(["-std=c11", "-Wall", "-Wextra", "-Werror", "-pedantic", "-I"])
        .arg(include_dir())
        .arg(&source)
        .arg("-o")
        .arg(&binary);
    run(compile, "compiling the probe against include/motiond.h");
    let printed = run(Command::new(&binary), "the probe");

    let have: BTreeSet<String> = printed.lines().map(str::to_owned).collect();
    let want = expected(&contract);
    let missing: Vec<&String> = want.difference(&have).collect();
    let extra: Vec<&String> = have.difference(&want).collect();
    assert!(
        missing.is_empty() && extra.is_empty(),
        "include/motiond.h differs from motion-ipc.\nRust says (C differs):\n  {}\nC says:\n  {}",
        missing
            .iter()
            .map(|s| s.as_str())
            .collect::<Vec<_>>()
            .join("\n  "),
        extra
            .iter()
            .map(|s| s.as_str())
            .collect::<Vec<_>>()
            .join("\n  ")
    );
}

#[test]
fn c_header_compiles_as_cpp() {
    let dir = work_dir();
    let source = dir.join("include.cpp");
    std::fs::write(
        &source,
        "#include \"motiond.h\"\nint main() { motiond_command_request_t r = \
         motiond_command_request(MOTIOND_COMMAND_KIND_STOP, MOTIOND_ALL_AXES, 1); \
         return r.kind == 1 ? 0 : 1; }\n",
    )
    .expect("write the C++ probe");
    let cxx = std::env::var("CXX").unwrap_or_else(|_| "c++".to_owned());
    let mut compile = Command::new(&cxx);
    compile
        .args([
            "-std=c++11",
            "-Wall",
            "-Wextra",
            "-Werror",
            "-pedantic",
            "-I",
        ])
        .arg(include_dir())
        .arg(&source)
        .arg("-o")
        .arg(dir.join("include-cpp"));
    run(compile, "compiling include/motiond.h as C++");
    run(Command::new(dir.join("include-cpp")), "the C++ probe");
}

#[test]
fn probe_names_every_field_and_value() {
    // The probe is generated from the same description as the expectations: every line
    // expected has a printf in the probe (so a header check cannot pass vacuously).
    let contract = contract();
    let source = probe_source(&contract);
    let expected = expected(&contract);
    let printfs = source.matches("printf(").count();
    assert_eq!(printfs, expected.len());
    assert!(expected.len() > 200, "{} checks", expected.len());
}
