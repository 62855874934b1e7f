//! Compiles the weak references to the manual's error handlers (csrc/callbacks.c) into
//! libtrol: Rust has no stable way to declare a weak symbol, a C compiler does.

fn main() {
    println!("cargo:rerun-if-changed=csrc/callbacks.c");
    cc::Build::new()
        .file("csrc/callbacks.c")
        .warnings(true)
        .compile("trolcallbacks");
}
