fn main() -> std::process::ExitCode {
    drapekit::cli::main()
}
