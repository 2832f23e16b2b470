//! `fluid-node` binary; all logic is in the library.

fn main() -> std::process::ExitCode {
    fluid_node::cli::main()
}
