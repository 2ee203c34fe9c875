fn main() -> std::process::ExitCode {
    dfem::cli::main()
}
