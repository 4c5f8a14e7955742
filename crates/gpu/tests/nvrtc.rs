//! The CUDA kernels compile with NVRTC (no GPU needed, only its library):
//! CI installs NVRTC (`scripts/nvrtc`) and sets `DRAPE_REQUIRE_NVRTC=1`, so
//! a kernel that does not compile fails CI. Without NVRTC and without that
//! variable the test says it skipped.

use drape_gpu::compile_kernels;

#[test]
fn the_cuda_kernels_compile_with_nvrtc() {
    let required = std::env::var_os("DRAPE_REQUIRE_NVRTC").is_some_and(|v| v == "1");
    // The Hopper build the GPU machines load, and NVRTC's default.
    for arch in [Some("compute_90"), None] {
        match compile_kernels(arch) {
            Ok(ptx) => {
                let text = ptx.to_src();
                for kernel in [
                    "truss_forces",
                    "quad_point_forces",
                    "triangle_forces",
                    "spring_forces",
                    "bending_forces",
                    "gather",
                    "gather_node_step",
                ] {
                    assert!(
                        text.contains(&format!(".entry {kernel}")),
                        "{kernel} in the PTX"
                    );
                }
                // (The PTX holds FMAs: CUDA's log and expm1 are written
                // with them. The kernels' own arithmetic has none, by
                // --fmad=false; the GPU check measures the difference.)
            }
            Err(drape_gpu::GpuError::NoDevice(why)) if !required => {
                eprintln!("skipped: {why} (set DRAPE_REQUIRE_NVRTC=1 to require it)");
                return;
            }
            Err(e) => panic!("{e}"),
        }
    }
}
