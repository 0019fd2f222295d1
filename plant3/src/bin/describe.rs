//! Writes TriplePendulum's modelDescription.xml and documentation page into
//! the directory given as argument (used by `fmu-build`).

fn main() -> std::process::ExitCode {
    fmi2_slave::xml::describe_main::<triple_pendulum_fmu::TriplePendulumFmu>(
        &triple_pendulum_fmu::documentation_html(),
    )
}
