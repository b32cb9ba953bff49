//! The `mbfmu` command: see [`mbfmu::cli`].

fn main() -> std::process::ExitCode {
    mbfmu::cli::main()
}
