//! Making one frame: render on the render thread, encode on the blocking pool, and pack the
//! binary message with its header. The header's stage times come from the frame's one timing
//! record ([`FrameTimes`]).

use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use super::pacing::Ticket;
use super::timing::FrameTimes;
use crate::encode;
use crate::encode::foveated::{self, LowPass};
use crate::encode::h264::H264Stream;
use crate::encode::hold::{self, Hold};
use crate::encode::{inset, inset_packed};
use crate::protocol::{
    encode_frame, Codec, ErrorCode, FrameHeader, GazeUsed, InsetHeader, ProtocolError,
    SolveProgress,
};
use crate::render::{FrameRequest, GpuLowPass, RenderHandle};
use crate::viewing::Viewing;

/// Everything needed to render a frame and write its header.
#[derive(Debug, Clone)]
pub struct FrameJob {
    pub ticket: Ticket,
    /// The sample's own position when prediction moved the gaze.
    pub raw: Option<[f32; 2]>,
    pub request: FrameRequest,
    pub codec: Codec,
    pub quality: u8,
    /// The session's H.264 stream, for `h264` sessions.
    pub h264: Option<Arc<Mutex<H264Stream>>>,
    /// Foveated encoding: the low-pass and the viewing geometry it is judged in.
    pub low_pass: Option<(LowPass, Viewing)>,
    /// Inset encoding: the inset's width in degrees and the viewing geometry.
    pub inset: Option<(f64, Viewing)>,
}

impl FrameJob {
    /// The job for `request` in a session opened by `hello`: its codec and foveated encoding.
    pub fn new(
        ticket: Ticket,
        raw: [f32; 2],
        mut request: FrameRequest,
        hello: &crate::protocol::Hello,
        h264: Option<Arc<Mutex<H264Stream>>>,
    ) -> FrameJob {
        let viewing = || Viewing::new(hello.display, hello.width, hello.height);
        // H.264 takes I420: the GPU converts where that is faster, unless the inset's packing
        // needs RGB first. The low-pass runs on the GPU wherever the conversion does.
        if hello.codec == Codec::H264 && hello.inset_deg.is_none() {
            request.readback = crate::render::Readback::I420Preferred;
        }
        if hello.foveated_encoding {
            request.low_pass = GpuLowPass::Preferred(LowPass::default());
        }
        FrameJob {
            ticket,
            raw: (request.gaze != raw).then_some(raw),
            request,
            codec: hello.codec,
            quality: hello.quality,
            h264,
            low_pass: hello
                .foveated_encoding
                .then(|| (LowPass::default(), viewing())),
            inset: hello.inset_deg.map(|deg| (deg, viewing())),
        }
    }
}

/// A frame ready for the socket.
#[derive(Debug)]
pub struct MadeFrame {
    pub bytes: Vec<u8>,
    pub times: FrameTimes,
}

/// A frame that could not be made, with its number so its credit can be returned.
#[derive(Debug)]
pub struct FrameFailed {
    pub frame: u64,
    pub error: ProtocolError,
}

pub async fn make(render: RenderHandle, job: FrameJob) -> Result<MadeFrame, FrameFailed> {
    let frame_no = job.ticket.frame;
    let failed = |what: &str, e: &dyn std::fmt::Display| FrameFailed {
        frame: frame_no,
        error: ProtocolError::new(
            ErrorCode::RenderFailed,
            format!("frame {frame_no}: {what}: {e}"),
        ),
    };
    let mut times = FrameTimes::new(job.ticket.trigger, job.ticket.arrived, Instant::now());
    let rendered = render
        .render(job.request.clone())
        .await
        .map_err(|e| failed("render", &e))?;
    ::metrics::counter!("fovea_frames_rendered_total").increment(1);
    let frame = rendered.frame;
    let secs = |ms: f64| Duration::from_secs_f64(ms.max(0.0) / 1e3);
    times.rendered(
        rendered.started,
        secs(frame.render_ms),
        secs(frame.readback_ms),
    );
    let (codec, quality, w, h) = (job.codec, job.quality, frame.width, frame.height);
    let stream = job.h264.clone();
    // Foveated encoding holds an H.264 stream's periphery (`encode::hold`) in the same geometry.
    let hold = job.low_pass.as_ref().map(|(_, viewing)| *viewing);
    // Unless the renderer filtered the frame already.
    let low_pass = job.low_pass.filter(|_| !frame.low_passed);
    let (inset, gaze) = (job.inset, job.request.gaze);
    let (rgba, i420) = (frame.rgba, frame.i420);
    let encoded = tokio::task::spawn_blocking(move || {
        let _span = tracing::debug_span!("encode", frame = frame_no).entered();
        let start = Instant::now();
        let g = [f64::from(gaze[0]), f64::from(gaze[1])];
        let rgba = match low_pass {
            Some((p, viewing)) => foveated::low_pass(&rgba, w, h, g, &viewing, &p),
            None => rgba,
        };
        let out = match (codec, stream, inset) {
            (Codec::H264, Some(stream), inset) => {
                let p = Picture {
                    rgba: &rgba,
                    i420: i420.as_deref(),
                    w,
                    h,
                };
                encode_h264(&stream, p, g, inset.as_ref(), hold.as_ref())
                    .map(|(f, i)| (f.bytes, Some(f.keyframe), i))
            }
            (_, _, Some((deg, viewing))) => {
                encode_inset(&rgba, w, h, g, &viewing, deg, codec, quality)
                    .map(|(b, i)| (b, None, Some(i)))
            }
            _ => encode::encode(&rgba, w, h, codec, quality).map(|b| (b, None, None)),
        };
        out.map(|(bytes, key, inset)| (bytes, key, inset, start, Instant::now()))
    })
    .await
    .map_err(|e| failed("encoder task", &e))?;
    let (image, keyframe, inset, encode_start, encode_end) =
        encoded.map_err(|e| failed("encode", &e))?;
    ::metrics::counter!("fovea_frame_bytes_total").increment(image.len() as u64);
    times.encode_start = encode_start;
    times.encode_end = encode_end;
    let used = |[x, y]: [f32; 2]| GazeUsed {
        x: f64::from(x),
        y: f64::from(y),
    };
    let t = &job.ticket;
    let header = FrameHeader {
        frame: t.frame,
        seq: t.gaze.map(|g| g.seq),
        t_ms: t.gaze.map(|g| g.t_ms),
        trigger: t.trigger,
        gaze: used(job.request.gaze),
        raw_gaze: job.raw.map(used),
        width: w,
        height: h,
        codec,
        keyframe,
        bytes: image.len(),
        inset,
        sampled: frame.sampled,
        unfoveated: frame.unfoveated,
        samples: t.samples,
        stages_ms: times.stages(),
        passes_ms: frame.passes_ms,
        radiosity: frame.radiosity.map(|p| SolveProgress {
            shots: p.shots,
            elements: p.elements,
            unshot: p.unshot,
            converged: p.converged,
        }),
    };
    Ok(MadeFrame {
        bytes: encode_frame(&header, &image),
        times,
    })
}

/// An inset frame's bytes (the downscaled whole frame, then the inset) and their header.
#[allow(clippy::too_many_arguments)]
fn encode_inset(
    rgba: &[u8],
    w: u32,
    h: u32,
    gaze: [f64; 2],
    viewing: &Viewing,
    inset_deg: f64,
    codec: Codec,
    quality: u8,
) -> Result<(Vec<u8>, InsetHeader), encode::EncodeError> {
    let plan = inset::plan(w, h, gaze, viewing, inset_deg, &LowPass::default());
    let (base, crop) = inset::split(rgba, w, h, &plan);
    let (bw, bh) = plan.base_size(w, h);
    let mut bytes = encode::encode(&base, bw, bh, codec, quality)?;
    let inset_bytes = encode::encode(&crop, plan.width, plan.height, codec, quality)?;
    let header = inset_header(&plan, w, h, inset_bytes.len(), None);
    bytes.extend_from_slice(&inset_bytes);
    Ok((bytes, header))
}

/// A read-back frame: RGBA, and its I420 planes where the GPU converted it.
struct Picture<'a> {
    rgba: &'a [u8],
    i420: Option<&'a [u8]>,
    w: u32,
    h: u32,
}

/// Encodes a frame with the session's H.264 stream: packed with its inset for an inset
/// session, else whole (from the GPU's I420 planes where there are some). With `hold` (the
/// viewing geometry of foveated encoding) the periphery is held (`encode::hold`).
fn encode_h264(
    stream: &Mutex<H264Stream>,
    p: Picture,
    g: [f64; 2],
    inset: Option<&(f64, Viewing)>,
    hold: Option<&Viewing>,
) -> Result<(encode::h264::H264Frame, Option<InsetHeader>), encode::EncodeError> {
    let mut s = stream
        .lock()
        .map_err(|_| encode::EncodeError::H264("the stream's lock was poisoned".into()))?;
    let s = &mut *s;
    let (w, h) = (p.w, p.h);
    if let Some((deg, viewing)) = inset {
        return encode_packed(s, p.rgba, (w, h), g, viewing, *deg, hold.is_some());
    }
    if let Some(viewing) = hold {
        s.hold_next(hold::thresholds(w, h, g, viewing, &Hold::default()));
    }
    match p.i420 {
        // Converted (and low-passed, if asked) on the GPU.
        Some(planes) => s.encode_i420(planes, w, h).map(|f| (f, None)),
        None => s.encode(p.rgba, w, h).map(|f| (f, None)),
    }
}

/// An H.264 inset frame: the base and the inset packed into one picture of the session's
/// stream (`encode::inset_packed`), and the header that says where each lies; with `hold`
/// (foveated encoding) the periphery of both parts is held (`encode::hold`).
fn encode_packed(
    stream: &mut H264Stream,
    rgba: &[u8],
    (w, h): (u32, u32),
    gaze: [f64; 2],
    viewing: &Viewing,
    inset_deg: f64,
    hold: bool,
) -> Result<(encode::h264::H264Frame, Option<InsetHeader>), encode::EncodeError> {
    let held = stream.held_inset();
    let plan = inset_packed::follow(held, w, h, gaze, viewing, inset_deg, &LowPass::default());
    let (base, crop) = inset::split(rgba, w, h, &plan);
    let (picture, layout) = inset_packed::pack(&base, &crop, &plan, w, h);
    if hold {
        let t =
            inset_packed::hold_thresholds(&plan, &layout, (w, h), gaze, viewing, &Hold::default());
        stream.hold_next(t);
    }
    let frame = stream.encode(&picture, layout.width, layout.height)?;
    stream.hold_inset(plan);
    let header = inset_header(&plan, w, h, 0, Some(layout));
    Ok((frame, Some(header)))
}

/// The header of an inset frame laid out by `plan` on a `w`×`h` frame.
fn inset_header(
    plan: &inset::InsetPlan,
    w: u32,
    h: u32,
    inset_bytes: usize,
    packed: Option<inset_packed::PackedLayout>,
) -> InsetHeader {
    let (base_width, base_height) = plan.base_size(w, h);
    InsetHeader {
        x: plan.x,
        y: plan.y,
        width: plan.width,
        height: plan.height,
        base_width,
        base_height,
        inset_bytes,
        feather: inset::FEATHER,
        packed,
    }
}

/// Whether `message` is the first failure of its kind (the message up to its first colon) the
/// client hears of: a broken frame repeats at the sample rate, the client is told once.
pub fn first_of_its_kind(told: &mut std::collections::HashSet<String>, message: &str) -> bool {
    told.insert(message.split(':').next().unwrap_or("").to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_kind_of_failure_is_told_once() {
        let mut told = Default::default();
        assert!(first_of_its_kind(
            &mut told,
            "render: device lost (frame 3)"
        ));
        assert!(!first_of_its_kind(
            &mut told,
            "render: device lost (frame 4)"
        ));
        assert!(first_of_its_kind(&mut told, "encode: out of memory"));
        assert!(!first_of_its_kind(&mut told, "encode: out of memory"));
    }
}
