//! Writes the C header of `gnss-attitude-ffi` (`ffi/include/gnss_attitude.h`) from its
//! sources with cbindgen, or with `--check` compares a fresh generation with the checked-in
//! header and fails when they differ.
//!
//! ```sh
//! cargo run -p gnss-attitude-ffi-header            # regenerate
//! cargo run -p gnss-attitude-ffi-header -- --check # CI
//! ```

use std::path::PathBuf;
use std::process::ExitCode;

fn main() -> ExitCode {
    let check = std::env::args().any(|a| a == "--check");
    let ffi = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let config = match cbindgen::Config::from_file(ffi.join("cbindgen.toml")) {
        Ok(c) => c,
        Err(e) => {
            eprintln!("gnss-attitude-ffi-header: cbindgen.toml: {e}");
            return ExitCode::FAILURE;
        }
    };
    let bindings = match cbindgen::Builder::new()
        .with_crate(&ffi)
        .with_config(config)
        .generate()
    {
        Ok(b) => b,
        Err(e) => {
            eprintln!("gnss-attitude-ffi-header: cbindgen failed: {e}");
            return ExitCode::FAILURE;
        }
    };
    let mut fresh = Vec::new();
    bindings.write(&mut fresh);
    let path = ffi.join("include").join("gnss_attitude.h");
    if check {
        let current = std::fs::read(&path).unwrap_or_default();
        if current != fresh {
            eprintln!(
                "gnss-attitude-ffi-header: {} differs from a fresh generation: run \
                 `cargo run -p gnss-attitude-ffi-header` and commit it",
                path.display()
            );
            return ExitCode::FAILURE;
        }
        println!("header up to date: {}", path.display());
    } else if let Err(e) = std::fs::write(&path, &fresh) {
        eprintln!("gnss-attitude-ffi-header: {}: {e}", path.display());
        return ExitCode::FAILURE;
    } else {
        println!("wrote {}", path.display());
    }
    ExitCode::SUCCESS
}
