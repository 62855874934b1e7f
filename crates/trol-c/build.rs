//! Compiles the weak references to the manual's error handlers (csrc/callbacks.c) into
//! libtrol: Rust has no stable way to declare a weak symbol, a C compiler does.

fn main() {
    println!("cargo:rerun-if-changed=csrc/callbacks.c");
    println!("cargo:rerun-if-changed=csrc/exports.map");
    // libtrol.so exports FatalError's default (a C symbol rustc's version script would hide);
    // GNU ld merges this script with rustc's.
    if std::env::var("CARGO_CFG_TARGET_OS").as_deref() == Ok("linux") {
        let map = std::path::Path::new(&std::env::var("CARGO_MANIFEST_DIR").unwrap())
            .join("csrc/exports.map");
        println!(
            "cargo:rustc-cdylib-link-arg=-Wl,--version-script={}",
            map.display()
        );
    }
    cc::Build::new()
        .file("csrc/callbacks.c")
        .warnings(true)
        .compile("trolcallbacks");
}
