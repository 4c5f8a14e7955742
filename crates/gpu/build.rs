//! Compiles the kernels' CPU build (kernels/host.c over kernels/step.h),
//! without contracting multiplies and adds, as the CPU driver does not.

fn main() {
    println!("cargo:rerun-if-changed=kernels/step.h");
    println!("cargo:rerun-if-changed=kernels/host.c");
    cc::Build::new()
        .file("kernels/host.c")
        .include("kernels")
        .flag("-std=c99")
        .flag_if_supported("-ffp-contract=off")
        // The per-thread functions keep each array's length beside it
        // (a node count, a slot count) whether or not a layout needs it.
        .flag_if_supported("-Wno-unused-parameter")
        .opt_level(2)
        .compile("drape_gpu_host");
}
