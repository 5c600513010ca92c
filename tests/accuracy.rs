//! The accuracy suite (`pathtracer accuracy --full`: 2^25 samples per pixel
//! in the accumulation case) passes on the CPU and on the GPU: every
//! analytic scene, image comparison and hard case.

use pt_render::Device;
use pt_render::accuracy::{self, Size};
use pt_tests::gpu;

#[test]
fn accuracy_suite_passes_on_cpu_and_gpu() {
    let ctx = gpu();
    let results = accuracy::run(&[Device::Cpu, Device::Gpu(&ctx)], Size::Full).expect("suite runs");
    let failed: Vec<_> = results.iter().filter(|r| !r.pass).collect();
    assert!(
        failed.is_empty(),
        "failed cases:\n{}",
        accuracy::markdown_table(&failed.into_iter().cloned().collect::<Vec<_>>())
    );
    // Both backends ran every scene case.
    let count = |backend: &str| results.iter().filter(|r| r.backend == backend).count();
    assert!(count("gpu") > 30 && count("gpu") == count("cpu"), "gpu {}, cpu {}", count("gpu"), count("cpu"));
    assert!(results.len() >= 80, "only {} cases", results.len());
}
