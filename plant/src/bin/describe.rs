//! Writes DoublePendulum's modelDescription.xml and documentation page into
//! the directory given as argument (used by `fmu-build`).

fn main() -> std::process::ExitCode {
    fmi2_slave::xml::describe_main::<double_pendulum_fmu::DoublePendulumFmu>(
        &double_pendulum_fmu::documentation_html(),
    )
}
