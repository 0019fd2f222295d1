//! `eigenmpc`: command-line front end (eigenmodes, closed-loop simulation).

mod cli;

fn main() -> std::process::ExitCode {
    cli::main()
}
