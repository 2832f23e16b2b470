//! Test shim for the `coupler-node` binary, so tests can spawn it through `CARGO_BIN_EXE_*`.

fn main() -> std::process::ExitCode {
    coupler_node::cli::main()
}
