//! The FMU variable tables of the manual, generated from the variable tables:
//! they live in the book's chapter on the FMUs' variables ([`TABLES_FILE`]),
//! `cargo run -p fmu-build` rewrites them between their markers, and a test
//! fails when that file differs from the generated text. (The module keeps
//! its name from the time the tables were in README.md.)

use crate::products::{controller_docs, plant_docs};
use fmi2_slave::table::markdown;

/// The file holding both tables between their markers, relative to the
/// repository root: the book's chapter on the FMUs' variables.
pub const TABLES_FILE: &str = "docs/book/src/fmu-variables.md";

/// Marker line before the plant table.
pub const PLANT_BEGIN: &str =
    "<!-- plant variables: generated from the variable table by `cargo run -p fmu-build` -->";
/// Marker line before the controller table.
pub const CONTROLLER_BEGIN: &str =
    "<!-- controller variables: generated from the variable table by `cargo run -p fmu-build` -->";
/// Marker line after each table.
pub const END: &str = "<!-- end of generated variables -->";

/// The plant table (`DoublePendulum`, `TriplePendulum`).
pub fn plant_table() -> Result<String, String> {
    markdown(&plant_docs())
}

/// The controller table (`EigenMPC`, `EigenMPC3`).
pub fn controller_table() -> Result<String, String> {
    markdown(&controller_docs())
}

/// `readme` (the text of [`TABLES_FILE`]) with both tables replaced by the
/// generated ones; an error when a marker is missing.
pub fn update(readme: &str) -> Result<String, String> {
    let text = replace(readme, PLANT_BEGIN, &plant_table()?)?;
    replace(&text, CONTROLLER_BEGIN, &controller_table()?)
}

fn replace(text: &str, begin: &str, table: &str) -> Result<String, String> {
    let start = text
        .find(begin)
        .ok_or_else(|| format!("{TABLES_FILE}: marker {begin} missing"))?
        + begin.len();
    let end = start
        + text[start..]
            .find(END)
            .ok_or_else(|| format!("{TABLES_FILE}: no {END} after {begin}"))?;
    Ok(format!("{}\n\n{table}\n{}", &text[..start], &text[end..]))
}
