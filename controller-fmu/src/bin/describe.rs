//! Writes EigenMPC's modelDescription.xml and documentation page into the
//! directory given as argument (used by `fmu-build`).

fn main() -> std::process::ExitCode {
    fmi2_slave::xml::describe_main::<eigenmpc_fmu::EigenMpcFmu>(&eigenmpc_fmu::documentation_html())
}
