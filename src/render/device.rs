use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use super::RenderError;

/// The adapter, device and queue every pass shares.
pub struct Gpu {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub info: wgpu::AdapterInfo,
    /// Set by the driver when the device is lost (reset, removed, destroyed): nothing rendered
    /// on it works again, and the render thread opens a new one.
    lost: Arc<AtomicBool>,
}

impl Gpu {
    /// Opens the best adapter available: a real GPU before a software one, Vulkan before GL.
    /// `WGPU_BACKEND` (e.g. `vulkan`, `gl`) restricts the choice.
    pub fn new() -> Result<Gpu, RenderError> {
        pollster::block_on(Self::open())
    }

    async fn open() -> Result<Gpu, RenderError> {
        // Native APIs first; GL only when they offer nothing, because probing GL through EGL
        // prints display-server complaints on headless machines.
        let tiers = match wgpu::Backends::from_env() {
            Some(b) => vec![b],
            None => vec![
                wgpu::Backends::VULKAN | wgpu::Backends::METAL | wgpu::Backends::DX12,
                wgpu::Backends::GL,
            ],
        };
        let mut tried = wgpu::Backends::empty();
        let mut chosen = None;
        for backends in tiers {
            tried |= backends;
            let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
            desc.backends = backends;
            let instance = wgpu::Instance::new(desc);
            let adapters = instance.enumerate_adapters(backends).await;
            for a in &adapters {
                let i = a.get_info();
                tracing::debug!(name = %i.name, backend = ?i.backend, kind = ?i.device_type, "adapter found");
            }
            chosen = adapters.into_iter().max_by_key(|a| rank(&a.get_info()));
            if chosen.is_some() {
                break;
            }
        }
        let adapter =
            chosen.ok_or_else(|| RenderError::NoAdapter(format!("tried backends {tried:?}")))?;
        let info = adapter.get_info();
        // Timestamps time each pass; without them only whole frames are timed.
        let required_features = adapter.features() & wgpu::Features::TIMESTAMP_QUERY;
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("fovea"),
                required_features,
                // The G-buffer writes four targets (normal + distance, albedo, blurred normal,
                // radiosity irradiance): 40 bytes per pixel by WebGPU's accounting, over the
                // default 32. Every desktop Vulkan, Metal and D3D12 adapter allows 64 or more.
                // The shading pass binds nine storage buffers (one over WebGPU's default of
                // eight: the coarse gather's lattice); Vulkan, Metal and D3D12 allow 16 or more.
                required_limits: wgpu::Limits {
                    max_color_attachment_bytes_per_sample: 40,
                    max_storage_buffers_per_shader_stage: 9,
                    ..wgpu::Limits::default()
                },
                ..Default::default()
            })
            .await
            .map_err(|source| RenderError::Device {
                adapter: info.name.clone(),
                source,
            })?;
        // Errors are caught per frame with error scopes; anything that escapes one is logged
        // rather than panicking the render thread that every session shares.
        device.on_uncaptured_error(Arc::new(|e| tracing::error!("uncaptured GPU error: {e:?}")));
        let lost = Arc::new(AtomicBool::new(false));
        let flag = lost.clone();
        device.set_device_lost_callback(move |reason, message| {
            tracing::error!("GPU device lost ({reason:?}): {message}");
            flag.store(true, Ordering::SeqCst);
        });
        tracing::info!(
            name = %info.name,
            backend = ?info.backend,
            kind = ?info.device_type,
            driver = %info.driver,
            driver_info = %info.driver_info,
            "GPU adapter chosen"
        );
        Ok(Gpu {
            device,
            queue,
            info,
            lost,
        })
    }

    /// Whether the device has been lost.
    pub fn is_lost(&self) -> bool {
        self.lost.load(Ordering::SeqCst)
    }

    /// One line naming the adapter, for logs, `welcome` and benchmark reports.
    pub fn summary(&self) -> String {
        let i = &self.info;
        format!(
            "{} ({:?}, {:?}, {} {})",
            i.name, i.backend, i.device_type, i.driver, i.driver_info
        )
    }
}

fn rank(info: &wgpu::AdapterInfo) -> (u8, u8) {
    let kind = match info.device_type {
        wgpu::DeviceType::DiscreteGpu => 4,
        wgpu::DeviceType::IntegratedGpu => 3,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Cpu => 1,
        wgpu::DeviceType::Other => 0,
    };
    let backend = match info.backend {
        wgpu::Backend::Vulkan | wgpu::Backend::Metal | wgpu::Backend::Dx12 => 2,
        wgpu::Backend::Gl => 1,
        _ => 0,
    };
    (kind, backend)
}
