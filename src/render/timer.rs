//! Per-pass GPU time from timestamp queries, where the adapter supports them: each pass's
//! label is also its timing label, so benchmarks and logs name passes the way the code does.

use std::collections::BTreeMap;

use super::targets::map_read;
use super::RenderError;

/// Two timestamps per pass; enough for every pass of one frame.
const MAX_PASSES: u32 = 32;

pub struct PassTimer {
    query_set: Option<wgpu::QuerySet>,
    resolve: wgpu::Buffer,
    read: wgpu::Buffer,
    labels: Vec<&'static str>,
    /// Nanoseconds per timestamp tick.
    period_ns: f64,
}

impl PassTimer {
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue) -> PassTimer {
        let enabled = device.features().contains(wgpu::Features::TIMESTAMP_QUERY);
        let query_set = enabled.then(|| {
            device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("pass timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: 2 * MAX_PASSES,
            })
        });
        let size = u64::from(2 * MAX_PASSES) * 8;
        let resolve = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("pass timestamps.resolve"),
            size,
            usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let read = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("pass timestamps.read"),
            size,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        PassTimer {
            query_set,
            resolve,
            read,
            labels: Vec::new(),
            period_ns: f64::from(queue.get_timestamp_period()),
        }
    }

    /// Whether passes are timed on the GPU (else only whole-frame wall time is known).
    pub fn enabled(&self) -> bool {
        self.query_set.is_some()
    }

    pub fn begin_frame(&mut self) {
        self.labels.clear();
    }

    fn slot(&mut self, label: &'static str) -> Option<(&wgpu::QuerySet, u32)> {
        if self.labels.len() as u32 >= MAX_PASSES {
            return None;
        }
        self.labels.push(label);
        let i = 2 * (self.labels.len() as u32 - 1);
        self.query_set.as_ref().map(|q| (q, i))
    }

    pub fn compute(&mut self, label: &'static str) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        self.slot(label)
            .map(|(query_set, i)| wgpu::ComputePassTimestampWrites {
                query_set,
                beginning_of_pass_write_index: Some(i),
                end_of_pass_write_index: Some(i + 1),
            })
    }

    /// Times a run of compute passes as one under `label`: the slot reserved here takes its
    /// start from the run's first pass and its end from its last (`part`).
    pub fn span(&mut self, label: &'static str) -> Option<u32> {
        self.slot(label).map(|(_, i)| i)
    }

    /// The timestamp writes of one pass of a `span`: the start on the first, the end on the last.
    pub fn part(
        &self,
        span: Option<u32>,
        first: bool,
        last: bool,
    ) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        let (query_set, i) = (self.query_set.as_ref()?, span?);
        (first || last).then_some(wgpu::ComputePassTimestampWrites {
            query_set,
            beginning_of_pass_write_index: first.then_some(i),
            end_of_pass_write_index: last.then_some(i + 1),
        })
    }

    pub fn render(&mut self, label: &'static str) -> Option<wgpu::RenderPassTimestampWrites<'_>> {
        self.slot(label)
            .map(|(query_set, i)| wgpu::RenderPassTimestampWrites {
                query_set,
                beginning_of_pass_write_index: Some(i),
                end_of_pass_write_index: Some(i + 1),
            })
    }

    /// Encodes the copy of this frame's timestamps to the readable buffer.
    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        if let (Some(q), n) = (&self.query_set, self.labels.len() as u32) {
            if n > 0 {
                encoder.resolve_query_set(q, 0..2 * n, &self.resolve, 0);
                encoder.copy_buffer_to_buffer(
                    &self.resolve,
                    0,
                    &self.read,
                    0,
                    u64::from(2 * n) * 8,
                );
            }
        }
    }

    /// Milliseconds per pass label (summed where a label repeats), after `submission` is done.
    pub fn read(
        &self,
        device: &wgpu::Device,
        submission: wgpu::SubmissionIndex,
    ) -> Result<BTreeMap<String, f64>, RenderError> {
        let mut out = BTreeMap::new();
        if self.query_set.is_none() || self.labels.is_empty() {
            return Ok(out);
        }
        let ticks: Vec<u64> = map_read(device, submission, &self.read, |b| {
            b.chunks_exact(8)
                .map(|c| u64::from_le_bytes(c.try_into().unwrap_or([0; 8])))
                .collect()
        })?;
        for (i, label) in self.labels.iter().enumerate() {
            let (start, end) = (ticks[2 * i], ticks[2 * i + 1]);
            let ms = end.saturating_sub(start) as f64 * self.period_ns / 1e6;
            *out.entry((*label).to_string()).or_insert(0.0) += ms;
        }
        Ok(out)
    }
}
