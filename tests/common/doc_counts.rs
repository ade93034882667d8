//! docs/architecture.md's layer table recomputed from the code, for
//! tests/architecture.rs: each module's lines (all its files together),
//! the lines of each file the row names (`` `validate.rs` 346 ``), and the
//! modules it imports.

use std::collections::BTreeSet;

/// What the table's rows are recomputed from.
pub struct Code<'a> {
    /// A module's lines, all its files together (None: no such module).
    pub module_lines: &'a dyn Fn(&str) -> Option<usize>,
    /// The lines of a file a module's row names (`stl.rs`, `mod.rs`,
    /// `gltf/materials.rs`: in the module's folder, or its own `bvh.rs`).
    pub file_lines: &'a dyn Fn(&str, &str) -> Option<usize>,
    /// The modules a module imports.
    pub imports: &'a dyn Fn(&str) -> BTreeSet<String>,
}

/// `n` as the doc writes it: 3,056.
fn thousands(n: usize) -> String {
    let digits = n.to_string();
    let mut out = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

/// `text` past the number it starts with (thousands separated by commas),
/// or None where it starts with no digit.
fn past_number(text: &str) -> Option<&str> {
    let bytes = text.as_bytes();
    let mut end = 0;
    while end < bytes.len()
        && (bytes[end].is_ascii_digit()
            || (bytes[end] == b','
                && end > 0
                && bytes.get(end + 1).is_some_and(u8::is_ascii_digit)))
    {
        end += 1;
    }
    (end > 0).then(|| &text[end..])
}

/// The lines cell of `module`'s row with every count recomputed: its
/// leading total, and the number after each file it names.
fn lines_cell(module: &str, cell: &str, code: &Code) -> Result<String, String> {
    let total = (code.module_lines)(module).ok_or(format!("`{module}`: no such module"))?;
    let rest = past_number(cell).ok_or(format!("`{module}`: its lines are no number: {cell}"))?;
    let mut out = thousands(total);
    // The rest alternates text and `name`: a count follows each `x.rs`.
    let mut parts = rest.split('`');
    out.push_str(parts.next().unwrap_or(""));
    while let (Some(name), Some(after)) = (parts.next(), parts.next()) {
        out.push('`');
        out.push_str(name);
        out.push('`');
        match after.strip_prefix(' ').and_then(past_number) {
            Some(tail) if name.ends_with(".rs") => {
                let lines = (code.file_lines)(module, name)
                    .ok_or(format!("`{module}`: no file `{name}`"))?;
                out.push(' ');
                out.push_str(&thousands(lines));
                out.push_str(tail);
            }
            _ => out.push_str(after),
        }
    }
    Ok(out)
}

/// `doc` with its layer table's counts and imports recomputed from `code`,
/// or what it names that the code lacks.
pub fn with_counts(doc: &str, code: &Code) -> Result<String, Vec<String>> {
    let mut problems = Vec::new();
    let mut out = Vec::new();
    for line in doc.lines() {
        let mut cells: Vec<String> = line.split(" | ").map(str::to_string).collect();
        let module = cells
            .get(1)
            .and_then(|m| m.strip_prefix('`')?.strip_suffix('`'));
        let (Some(module), 5) = (module, cells.len()) else {
            out.push(line.to_string());
            continue;
        };
        let module = module.to_string();
        match lines_cell(&module, &cells[2], code) {
            Ok(cell) => cells[2] = cell,
            Err(e) => problems.push(e),
        }
        let imports = Vec::from_iter((code.imports)(&module));
        let last = if imports.is_empty() {
            "—".to_string()
        } else {
            imports.join(", ")
        };
        cells[4] = format!("{last} |");
        out.push(cells.join(" | "));
    }
    if problems.is_empty() {
        Ok(out.join("\n") + "\n")
    } else {
        Err(problems)
    }
}
