//! The accuracy suite (`pathtracer accuracy --full`: 1e6 hit points, 1e7
//! rays, 2^25 samples per pixel) passes on the CPU
//! and on the GPU: every analytic scene, hard case and sampling test.

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
    // Both backends ran the scene cases.
    assert!(results.iter().any(|r| r.backend == "gpu") && results.iter().any(|r| r.backend == "cpu"));
    assert!(results.len() > 80, "only {} cases", results.len());
}
