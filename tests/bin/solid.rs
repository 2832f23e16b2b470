//! Test shim for the `solid-node` binary, so tests can spawn it through `CARGO_BIN_EXE_*`.

fn main() -> std::process::ExitCode {
    solid_node::cli::main()
}
