//! `fluid-node` binary; all logic is in the library.

fn main() -> std::process::ExitCode {
    std::process::ExitCode::SUCCESS
}
