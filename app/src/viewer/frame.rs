//! What the desktop viewer puts on screen: egui's frame (the panel, and the
//! traced image drawn by the session's paint callback), the window
//! surface's configuration, and screenshots of the window's content.

use std::path::Path;

use anyhow::{Result, anyhow};
use pt_render::GpuContext;
use pt_render::output;
use winit::dpi::PhysicalSize;

use super::Viewer;

impl Viewer {
    pub(super) fn draw(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        view: &wgpu::TextureView,
        paint_jobs: &[egui::ClippedPrimitive],
        screen: &egui_wgpu::ScreenDescriptor,
    ) {
        let mut pass = encoder
            .begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("viewer"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                ..Default::default()
            })
            .forget_lifetime();
        self.egui_renderer.render(&mut pass, paint_jobs, screen);
    }

    pub(super) fn offscreen_target(&self) -> wgpu::Texture {
        self.ctx.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("screenshot"),
            size: wgpu::Extent3d { width: self.config.width, height: self.config.height, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: self.config.format,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        })
    }

    /// Copies the composited frame (image and panel) to a PNG.
    pub(super) fn save_screenshot(&self, target: &wgpu::Texture, path: &Path) -> Result<()> {
        let (w, h) = (self.config.width, self.config.height);
        let row = (w * 4).div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
        let buffer = self.ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("screenshot"),
            size: row as u64 * h as u64,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
        encoder.copy_texture_to_buffer(
            target.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: &buffer,
                layout: wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(row), rows_per_image: Some(h) },
            },
            target.size(),
        );
        self.ctx.queue.submit([encoder.finish()]);
        let bytes = self.ctx.read_buffer(&buffer, buffer.size())?;
        let bgra = matches!(self.config.format, wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb);
        let mut pixels = Vec::with_capacity((w * h) as usize);
        for y in 0..h as usize {
            for x in 0..w as usize {
                let p = &bytes[y * row as usize + x * 4..][..4];
                let (r, b) = if bgra { (p[2], p[0]) } else { (p[0], p[2]) };
                pixels.push(u32::from_le_bytes([r, p[1], b, 255]));
            }
        }
        output::write_png(path, w, h, &pixels)?;
        Ok(())
    }
}

/// A surface configuration for `size`, preferring a non-sRGB 8-bit format:
/// the display buffer already holds sRGB-encoded bytes.
pub(super) fn surface_config(
    ctx: &GpuContext,
    surface: &wgpu::Surface<'_>,
    size: PhysicalSize<u32>,
) -> Result<wgpu::SurfaceConfiguration> {
    let caps = surface.get_capabilities(ctx.adapter());
    let format = caps
        .formats
        .iter()
        .copied()
        .find(|f| matches!(f, wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Rgba8Unorm))
        .or_else(|| caps.formats.first().copied())
        .ok_or_else(|| anyhow!("the window surface offers no format this adapter can render to"))?;
    let present_mode = if caps.present_modes.contains(&wgpu::PresentMode::Fifo) {
        wgpu::PresentMode::Fifo
    } else {
        caps.present_modes.first().copied().unwrap_or(wgpu::PresentMode::Fifo)
    };
    Ok(wgpu::SurfaceConfiguration {
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
        format,
        color_space: wgpu::SurfaceColorSpace::Auto,
        width: size.width.max(1),
        height: size.height.max(1),
        present_mode,
        desired_maximum_frame_latency: 2,
        alpha_mode: caps.alpha_modes.first().copied().unwrap_or(wgpu::CompositeAlphaMode::Auto),
        view_formats: vec![],
    })
}
