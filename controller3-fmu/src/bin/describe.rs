//! Writes EigenMPC3's modelDescription.xml and documentation page into the
//! directory given as argument (used by `fmu-build`).

fn main() -> std::process::ExitCode {
    fmi2_slave::xml::describe_main::<eigenmpc3_fmu::EigenMpc3Fmu>(
        &eigenmpc3_fmu::documentation_html(),
    )
}
