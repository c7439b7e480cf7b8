//! The `hexray` command line: subcommands, defaults and exit statuses, in `cli/` (one module
//! per subcommand). Everything else lives in the library.

mod cli;

fn main() -> std::process::ExitCode {
    cli::run()
}
