//! `solid-node` binary; all logic is in the library.

fn main() -> std::process::ExitCode {
    solid_node::cli::main()
}
