//! GPU timestamps around one compute pass.

use super::{GpuContext, GpuError};

/// Times one compute pass with GPU timestamp queries, where the adapter has
/// them.
pub struct GpuTimer {
    queries: wgpu::QuerySet,
    resolve_buf: wgpu::Buffer,
    read_buf: wgpu::Buffer,
    /// Nanoseconds per timestamp tick.
    period_ns: f64,
}

impl GpuTimer {
    /// A timer, or `None` when the adapter has no timestamp queries.
    pub fn new(ctx: &GpuContext) -> Option<Self> {
        if !ctx.device.features().contains(wgpu::Features::TIMESTAMP_QUERY) {
            return None;
        }
        let queries = ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("frame timestamps"),
            ty: wgpu::QueryType::Timestamp,
            count: 2,
        });
        let resolve_buf = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("timestamps"),
            size: 16,
            usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let read_buf = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("timestamps readback"),
            size: 16,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Some(Self { queries, resolve_buf, read_buf, period_ns: ctx.queue.get_timestamp_period() as f64 })
    }

    /// Timestamp writes at the beginning and end of a compute pass.
    pub fn pass_writes(&self) -> wgpu::ComputePassTimestampWrites<'_> {
        wgpu::ComputePassTimestampWrites {
            query_set: &self.queries,
            beginning_of_pass_write_index: Some(0),
            end_of_pass_write_index: Some(1),
        }
    }

    /// Records the copy of the two timestamps to the readable buffer.
    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        encoder.resolve_query_set(&self.queries, 0..2, &self.resolve_buf, 0);
        encoder.copy_buffer_to_buffer(&self.resolve_buf, 0, &self.read_buf, 0, 16);
    }

    /// Milliseconds between the two timestamps of the last timed pass
    /// (waits for the GPU).
    pub fn read_ms(&self, ctx: &GpuContext) -> Result<f64, GpuError> {
        let (tx, rx) = std::sync::mpsc::channel();
        self.read_buf.map_async(wgpu::MapMode::Read, .., move |r| {
            let _ = tx.send(r);
        });
        ctx.wait()?;
        rx.recv().map_err(|e| GpuError::DeviceLost(e.to_string()))?.map_err(|e| GpuError::DeviceLost(e.to_string()))?;
        let t: [u64; 2] = {
            let view = self.read_buf.get_mapped_range(..).map_err(|e| GpuError::Validation(e.to_string()))?;
            bytemuck::pod_read_unaligned(&view[..16])
        };
        self.read_buf.unmap();
        Ok(t[1].saturating_sub(t[0]) as f64 * self.period_ns * 1e-6)
    }
}
