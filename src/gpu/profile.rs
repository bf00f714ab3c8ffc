//! Per-pass times of a frame. With timestamp queries (Vulkan has them; lavapipe too) the
//! frame is one submission and a timestamp is written between passes; without them the
//! profiling mode submits and waits after each pass and times the passes on the CPU.

use super::Gpu;
use anyhow::{anyhow, Result};
use serde::Serialize;
use std::time::Instant;

/// How a frame is submitted and its passes timed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Profiling {
    /// One submission a frame; each pass's GPU time from timestamp queries.
    Timestamps,
    /// One submission and a wait per pass; each pass's wall time on the CPU (slower: the
    /// CPU waits for every pass; for adapters without timestamp queries).
    Serialized,
    /// One submission a frame and no per-pass times.
    Off,
}

impl Profiling {
    /// Timestamps where the adapter has them and they time the passes, else serialized (so
    /// that run records keep per-pass times). Lavapipe (Vulkan on the CPU) has timestamp
    /// queries but they do not time its passes: on `cornell-orbit` at 256 VPLs, 128x128 its
    /// timestamps gave the gather 10 ms and the pull-push 1167 ms where serialized passes
    /// took 1344 ms and 205 ms, with the same frame time (2.5 s vs 2.7 s); llvmpipe's GL
    /// timestamps agree with serialized passes (gather 1383 vs 1283 ms, splat 697 vs 690 ms).
    pub fn default_for(gpu: &Gpu) -> Profiling {
        let lavapipe = gpu.adapter.backend == format!("{:?}", wgpu::Backend::Vulkan)
            && gpu.adapter.device_type == format!("{:?}", wgpu::DeviceType::Cpu);
        if has_timestamps(gpu) && !lavapipe {
            Profiling::Timestamps
        } else {
            Profiling::Serialized
        }
    }
}

/// Features that timestamps between passes need.
pub const TIMESTAMP_FEATURES: wgpu::Features =
    wgpu::Features::TIMESTAMP_QUERY.union(wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS);

/// Whether `gpu`'s device can write timestamps between passes.
pub fn has_timestamps(gpu: &Gpu) -> bool {
    gpu.device.features().contains(TIMESTAMP_FEATURES)
}

/// The timestamp query set of a frame: one timestamp before the first pass and one after
/// each pass.
pub(crate) struct Timestamps {
    set: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    pub(crate) staging: wgpu::Buffer,
    count: u32,
    /// Nanoseconds per tick.
    period: f32,
}

impl Timestamps {
    pub(crate) fn new(gpu: &Gpu, passes: u32) -> Self {
        let count = passes + 1;
        let set = gpu.device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("pass timestamps"),
            ty: wgpu::QueryType::Timestamp,
            count,
        });
        let bytes = count as u64 * 8;
        let resolve = gpu.buffer(
            "timestamps",
            bytes,
            wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
        );
        let staging = gpu.buffer(
            "timestamps readback",
            bytes,
            wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        );
        Timestamps {
            set,
            resolve,
            staging,
            count,
            period: gpu.queue.get_timestamp_period(),
        }
    }

    /// Resolves the first `used` timestamps into the staging buffer (map it after the
    /// submission).
    pub(crate) fn resolve(&self, enc: &mut wgpu::CommandEncoder, used: u32) {
        let used = used.min(self.count);
        enc.resolve_query_set(&self.set, 0..used, &self.resolve, 0);
        enc.copy_buffer_to_buffer(&self.resolve, 0, &self.staging, 0, used as u64 * 8);
    }

    /// Seconds of each pass from the mapped staging buffer's ticks.
    pub(crate) fn seconds(&self, ticks: &[u64]) -> Vec<f64> {
        ticks
            .windows(2)
            .map(|w| w[1].saturating_sub(w[0]) as f64 * self.period as f64 * 1e-9)
            .collect()
    }
}

/// Records a frame's passes into one encoder (or, serialized, one submission each) and
/// times them.
pub(crate) struct Recorder<'a> {
    gpu: &'a Gpu,
    mode: Profiling,
    timestamps: Option<&'a Timestamps>,
    pub(crate) enc: wgpu::CommandEncoder,
    t0: Instant,
    /// The passes ended, in order.
    pub(crate) passes: Vec<&'static str>,
    /// Serialized: seconds per pass, in order.
    pub(crate) cpu: Vec<f64>,
}

impl<'a> Recorder<'a> {
    pub(crate) fn new(gpu: &'a Gpu, mode: Profiling, timestamps: Option<&'a Timestamps>) -> Self {
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        let timestamps = timestamps.filter(|_| mode == Profiling::Timestamps);
        if let Some(t) = timestamps {
            enc.write_timestamp(&t.set, 0);
        }
        Recorder {
            gpu,
            mode,
            timestamps,
            enc,
            t0: Instant::now(),
            passes: Vec::new(),
            cpu: Vec::new(),
        }
    }

    /// Ends the pass `name`: a timestamp, or (serialized) a submission and a wait.
    pub(crate) fn end_pass(&mut self, name: &'static str) -> Result<()> {
        self.passes.push(name);
        match self.mode {
            Profiling::Timestamps => {
                if let Some(t) = self.timestamps {
                    self.enc.write_timestamp(&t.set, self.passes.len() as u32);
                }
            }
            Profiling::Serialized => {
                let enc = std::mem::replace(
                    &mut self.enc,
                    self.gpu.device.create_command_encoder(&Default::default()),
                );
                self.gpu.queue.submit([enc.finish()]);
                self.gpu.wait()?;
                let now = Instant::now();
                self.cpu.push((now - self.t0).as_secs_f64());
                self.t0 = now;
            }
            Profiling::Off => {}
        }
        Ok(())
    }

    /// Submits what is recorded, with the timestamps resolved.
    pub(crate) fn submit(mut self) {
        if let Some(t) = self.timestamps {
            t.resolve(&mut self.enc, self.passes.len() as u32 + 1);
        }
        self.gpu.queue.submit([self.enc.finish()]);
    }
}

/// Maps `buffers` (MAP_READ, after their submission), waits once, and returns their bytes.
pub(crate) fn read_mapped(gpu: &Gpu, buffers: &[(&wgpu::Buffer, u64)]) -> Result<Vec<Vec<u8>>> {
    let (tx, rx) = std::sync::mpsc::channel();
    for (i, (b, size)) in buffers.iter().enumerate() {
        let tx = tx.clone();
        b.slice(..*size).map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send((i, r));
        });
    }
    drop(tx);
    gpu.wait()?;
    for (i, r) in rx.iter() {
        r.map_err(|e| anyhow!("readback of buffer {i} failed: {e}"))?;
    }
    buffers
        .iter()
        .map(|(b, size)| {
            let data = b
                .get_mapped_range(..*size)
                .map_err(|e| anyhow!("readback map failed: {e:?}"))?
                .to_vec();
            b.unmap();
            Ok(data)
        })
        .collect()
}
