//! Test shim for the `fluid-node` binary, so tests can spawn it through `CARGO_BIN_EXE_*`.

fn main() -> std::process::ExitCode {
    fluid_node::cli::main()
}
