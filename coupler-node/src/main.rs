//! `coupler-node` binary; all logic is in the library.

fn main() -> std::process::ExitCode {
    coupler_node::cli::main()
}
