//! Keeps src/lib.rs in step with ln.h: every `LN_EXPORT` function, every struct and callback
//! typedef of the header has a declaration in the sys crate with the same number of
//! parameters (fields), and the crate declares nothing the header does not have.  A function
//! added to ln.h without a binding fails here.  Also checks the generated error table and the
//! version numbers against the running library.

use std::collections::BTreeMap;
use std::ffi::CStr;

use links_and_nodes_sys as sys;

const HEADER: &str = include_str!(env!("LN_HEADER_PATH"));
const BINDINGS: &str = include_str!("../src/lib.rs");

/// The text without C (/* */) or Rust (//) comments.
fn strip_comments(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while !rest.is_empty() {
        if let Some(r) = rest.strip_prefix("/*") {
            rest = r.split_once("*/").map_or("", |(_, after)| after);
            out.push(' ');
        } else if let Some(r) = rest.strip_prefix("//") {
            rest = r.split_once('\n').map_or("", |(_, after)| after);
            out.push('\n');
        } else {
            let c = rest.chars().next().unwrap();
            out.push(c);
            rest = &rest[c.len_utf8()..];
        }
    }
    out
}

/// The text between the '(' at `open` and its matching ')'.
fn parenthesized(text: &str, open: usize) -> &str {
    let mut depth = 0;
    for (i, c) in text[open..].char_indices() {
        match c {
            '(' => depth += 1,
            ')' => {
                depth -= 1;
                if depth == 0 {
                    return &text[open + 1..open + i];
                }
            }
            _ => {}
        }
    }
    panic!("unbalanced parentheses after {:?}", &text[open..open + 40]);
}

/// Number of comma-separated items at parenthesis depth 0 ("void" and "" count 0).
fn count_items(list: &str) -> usize {
    let mut depth = 0;
    let mut items = vec![String::new()];
    for c in list.chars() {
        match c {
            '(' => depth += 1,
            ')' => depth -= 1,
            ',' if depth == 0 => {
                items.push(String::new());
                continue;
            }
            _ => {}
        }
        items.last_mut().unwrap().push(c);
    }
    items
        .iter()
        .filter(|i| !i.trim().is_empty() && i.trim() != "void")
        .count()
}

fn ident_before(text: &str, end: usize) -> String {
    let head = text[..end].trim_end();
    let start = head
        .rfind(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .map_or(0, |i| i + 1);
    head[start..].to_string()
}

/// name -> parameter count of each LN_EXPORT function of ln.h.
fn header_functions(header: &str) -> BTreeMap<String, usize> {
    let mut out = BTreeMap::new();
    for (at, _) in header.match_indices("LN_EXPORT") {
        if header[..at].trim_end().ends_with("#define") {
            continue; // the macro's own definition
        }
        let decl = &header[at + "LN_EXPORT".len()..];
        let decl = &decl[..decl.find(';').expect("declaration without ';'")];
        let open = decl.find('(').expect("function without '('");
        out.insert(
            ident_before(decl, open),
            count_items(parenthesized(decl, open)),
        );
    }
    out
}

/// (kind, name) -> count of ln.h's typedefs: "struct" field counts, "opaque" 0, "callback"
/// parameter counts.
fn header_types(header: &str) -> BTreeMap<(String, String), usize> {
    let mut out = BTreeMap::new();
    for part in header.split("typedef ").skip(1) {
        if let Some(rest) = part.strip_prefix("struct ") {
            let name: String = rest
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                .collect();
            let after = rest[name.len()..].trim_start();
            if let Some(body) = after.strip_prefix('{') {
                let body = &body[..body.find('}').unwrap()];
                let fields = body
                    .split(';')
                    .filter(|f| !f.trim().is_empty())
                    .map(|f| f.matches(',').count() + 1)
                    .sum();
                out.insert(("struct".to_string(), name), fields);
            } else {
                out.insert(("opaque".to_string(), name), 0);
            }
        } else if let Some(star) = part.find("(*") {
            let close = part[star..].find(')').unwrap() + star;
            let name = part[star + 2..close].trim().to_string();
            let open = part[close..].find('(').unwrap() + close;
            out.insert(
                ("callback".to_string(), name),
                count_items(parenthesized(part, open)),
            );
        } else if !part.starts_with("enum") {
            panic!("ln.h: a typedef this test does not know: {:?}", &part[..40]);
        }
    }
    out
}

fn binding_functions(src: &str) -> BTreeMap<String, usize> {
    let block = &src[src.find("extern \"C\" {").expect("no extern block")..];
    let mut out = BTreeMap::new();
    for part in block.split("pub fn ").skip(1) {
        let open = part.find('(').unwrap();
        out.insert(
            part[..open].trim().to_string(),
            count_items(parenthesized(part, open)),
        );
    }
    out
}

fn binding_types(src: &str) -> BTreeMap<(String, String), usize> {
    let mut out = BTreeMap::new();
    let list = &src[src.find("opaque!(\n").expect("no opaque! list") + 8..];
    for name in list[..list.find(')').unwrap()].split(',') {
        if !name.trim().is_empty() {
            out.insert(("opaque".to_string(), name.trim().to_string()), 0);
        }
    }
    for part in src.split("pub struct ").skip(1) {
        let name = part[..part.find([' ', '{']).unwrap()].trim().to_string();
        if name.starts_with('$') {
            continue; // the opaque! macro's template
        }
        let body = &part[part.find('{').unwrap() + 1..part.find('}').unwrap()];
        out.insert(("struct".to_string(), name), body.matches("pub ").count());
    }
    for part in src.split("pub type ").skip(1) {
        let name = part[..part.find('=').unwrap()].trim().to_string();
        let open = part.find("fn(").expect("callback type without fn(") + 2;
        out.insert(
            ("callback".to_string(), name),
            count_items(parenthesized(part, open)),
        );
    }
    out
}

fn compare<K: Ord + std::fmt::Debug>(
    what: &str,
    header: &BTreeMap<K, usize>,
    rust: &BTreeMap<K, usize>,
) {
    let mut problems = Vec::new();
    for (name, count) in header {
        match rust.get(name) {
            None => problems.push(format!("{what} {name:?} of ln.h has no binding")),
            Some(c) if c != count => problems.push(format!(
                "{what} {name:?}: ln.h has {count} parameters/fields, the binding {c}"
            )),
            _ => {}
        }
    }
    for name in rust.keys() {
        if !header.contains_key(name) {
            problems.push(format!("{what} {name:?} is bound but not in ln.h"));
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

#[test]
fn every_function_of_ln_h_is_bound_with_its_parameter_count() {
    let header = header_functions(&strip_comments(HEADER));
    assert!(header.len() > 50, "parsed only {} functions", header.len());
    assert_eq!(header.get("ln_read"), Some(&5));
    assert_eq!(header.get("ln_error_count"), Some(&0));
    compare(
        "function",
        &header,
        &binding_functions(&strip_comments(BINDINGS)),
    );
}

#[test]
fn a_function_added_to_the_header_without_a_binding_fails() {
    let header = format!(
        "{HEADER}\nLN_EXPORT int ln_something_new(ln_client* c, int x);\n\
         LN_EXPORT int ln_read(ln_inport* p);\n"
    );
    let header = header_functions(&strip_comments(&header));
    let outcome = std::panic::catch_unwind(|| {
        compare(
            "function",
            &header,
            &binding_functions(&strip_comments(BINDINGS)),
        )
    });
    let message = *outcome.unwrap_err().downcast::<String>().unwrap();
    assert!(
        message.contains("\"ln_something_new\" of ln.h has no binding"),
        "{message}"
    );
    assert!(
        message.contains("\"ln_read\": ln.h has 1 parameters/fields, the binding 5"),
        "{message}"
    );
}

#[test]
fn every_type_of_ln_h_is_bound_with_its_field_count() {
    let header = header_types(&strip_comments(HEADER));
    assert_eq!(
        header.get(&("struct".to_string(), "ln_parameter_desc".to_string())),
        Some(&9)
    );
    compare("type", &header, &binding_types(&strip_comments(BINDINGS)));
}

#[test]
fn the_generated_error_table_is_the_librarys() {
    // SAFETY: plain queries of static data.
    let count = unsafe { sys::ln_error_count() };
    let mut seen = Vec::new();
    macro_rules! collect {
        ($(($name:ident, $code:literal, $text:literal)),* $(,)?) => {
            $(seen.push((stringify!($name), $code, $text));)*
        };
    }
    sys::ln_errno_map!(collect);
    assert_eq!(seen.len() as i32, count);
    for (name, code, text) in seen {
        // SAFETY: static strings of libln.
        let lib_name = unsafe { CStr::from_ptr(sys::ln_error_name(code)) };
        let lib_text = unsafe { CStr::from_ptr(sys::ln_strerror(code)) };
        assert_eq!(lib_name.to_str().unwrap(), name);
        assert_eq!(lib_text.to_str().unwrap(), text);
    }
    assert_eq!(sys::LN_ETIMEOUT, -3);
}

#[test]
fn the_version_constants_are_the_headers_and_the_library_accepts_them() {
    let header = strip_comments(HEADER);
    let define = |name: &str| -> i32 {
        let at = header.find(&format!("#define {name} ")).unwrap() + name.len() + 9;
        header[at..]
            .split_whitespace()
            .next()
            .unwrap()
            .parse()
            .unwrap()
    };
    assert_eq!(define("LN_VERSION_MAJOR"), sys::LN_VERSION_MAJOR);
    assert_eq!(define("LN_VERSION_MINOR"), sys::LN_VERSION_MINOR);
    let version = format!(
        "{}.{}.{}",
        define("LN_VERSION_MAJOR"),
        define("LN_VERSION_MINOR"),
        define("LN_VERSION_PATCH")
    );
    assert_eq!(
        env!("CARGO_PKG_VERSION"),
        version,
        "the crates' version is ln.h's"
    );
    // SAFETY: a plain query.
    let rc = unsafe { sys::ln_version_check(sys::LN_VERSION_MAJOR, sys::LN_VERSION_MINOR) };
    assert_eq!(rc, sys::LN_OK);
}
