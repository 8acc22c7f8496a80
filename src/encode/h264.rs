//! H.264 for one session: an openh264 encoder that outputs every frame at once (no B-frames,
//! no frame skipping, no reordering: a browser's WebCodecs decoder shows each frame as it
//! arrives), a keyframe at the start, on request, after a size change and every
//! `keyframe_every`, and the bitrate held by a quantiser range that `rate_guard` picks (it
//! looks every `GUARD_CHECK_MS` of the stream's clock; only a switch costs a keyframe).
//!
//! Frames are converted from RGBA by `encode::yuv` (BT.601 full range, rounded; openh264's own
//! converter truncates, which FLIP counts) and the
//! stream's VUI says so, so decoders turn them back into the same colours. openh264 built
//! from source (the default) is not covered by Cisco's patent licence; building with the
//! `openh264-libloading` feature loads Cisco's binary instead (see README, "Licences").

use std::time::{Duration, Instant};

use openh264::encoder::{
    BitRate, Encoder, EncoderConfig, FrameRate, FrameType, Profile, QpRange, RateControlMode,
    SpsPpsStrategy, UsageType, VuiConfig,
};
use openh264::formats::YUVSource;

use super::shown::Shown;
use super::yuv::I420;

/// A frame as the renderer hands it over.
enum Picture<'a> {
    Rgba(&'a [u8]),
    I420(&'a [u8]),
}

use openh264::{OpenH264API, Timestamp};

use super::rate_guard::{RateGuard, Switch};

use super::EncodeError;

/// The bitrate a session gets when its hello names none, kbit/s (about 0.06 bits per pixel
/// of 1280×720 at 60 fps).
pub const DEFAULT_KBPS: u32 = 4000;
/// The bitrates a session may ask for, kbit/s.
pub const KBPS_RANGE: (u32, u32) = (100, 50_000);
/// A keyframe at least this often by default. The WebSocket loses no frame and a client whose
/// decoder fails asks for a keyframe, so this is only a backstop: at 2 s, which it was, a
/// still `gallery` session at 640×480 on a software adapter (~6 frames a second) spent 241 of
/// its 375 kbit/s on 60 kB keyframes (docs/keyframes.md).
pub const DEFAULT_KEYFRAME_S: f64 = 10.0;
/// The keyframe periods a session may ask for, seconds.
pub const KEYFRAME_S_RANGE: (f64, f64) = (0.1, 60.0);
/// How often, by the stream's clock, the rate guard may switch the quantiser's range back to
/// quality (`RateGuard::decide`'s check); a switch costs a keyframe, a check that keeps the
/// range costs nothing. 2 s: the keyframe period the guard's back-off was set with.
pub const GUARD_CHECK_MS: u64 = 2000;

/// H.264 settings of one stream.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct H264Config {
    pub kbps: u32,
    pub keyframe_every: Duration,
}

impl Default for H264Config {
    fn default() -> Self {
        H264Config {
            kbps: DEFAULT_KBPS,
            keyframe_every: Duration::from_secs_f64(DEFAULT_KEYFRAME_S),
        }
    }
}

/// The openh264 to use: Cisco's binary named by `FOVEA_OPENH264_LIB` when built with the
/// `openh264-libloading` feature, else the one built from source.
pub(super) fn api() -> Result<OpenH264API, EncodeError> {
    #[cfg(feature = "openh264-libloading")]
    if let Some(path) = std::env::var_os("FOVEA_OPENH264_LIB") {
        // SAFETY: the library is Cisco's openh264 build, named by whoever runs the server;
        // loading it runs its initialisers, which is what it is for.
        return unsafe { OpenH264API::from_blob_path_unchecked(&path) }
            .map_err(|e| EncodeError::H264(format!("loading {}: {e}", path.to_string_lossy())));
    }
    Ok(OpenH264API::from_source())
}

/// Silences openh264's own log before its first frame initialises it. The crate sets the
/// level only after initialising, and initialising with frame skipping off prints a warning
/// to stderr ("bitrate can't be controlled … without enabling skip frame") once per stream:
/// a raw line in the server's log (which `--log-format json` promises is JSON) for every
/// H.264 session. We keep skipping off on purpose (every frame is shown), and the quantiser
/// range bounds the rate instead (docs/encoding.md).
fn quiet(encoder: &mut Encoder) {
    let mut level = openh264_sys2::WELS_LOG_QUIET as std::os::raw::c_int;
    // SAFETY: the encoder was created by `with_api_config` and is not yet initialised;
    // openh264 accepts this option before initialisation (welsEncoderExt.cpp, SetOption), and
    // reads an int through the pointer, which lives for the call.
    let rc = unsafe {
        encoder.raw_api().set_option(
            openh264_sys2::ENCODER_OPTION_TRACE_LEVEL,
            std::ptr::addr_of_mut!(level).cast(),
        )
    };
    if rc != 0 {
        tracing::debug!(
            rc,
            "openh264 refused its log level; its warnings may show on stderr"
        );
    }
}

/// One session's encoder and its keyframe bookkeeping.
pub struct H264Stream {
    config: H264Config,
    encoder: Option<Encoder>,
    size: (u32, u32),
    /// By the stream's clock (ms), as are the guard's checks.
    last_keyframe: Option<u64>,
    last_check: u64,
    keyframe_asked: bool,
    /// The stream's clock: rate control spends bits by the time between frames.
    started: Instant,
    last_ms: u64,
    yuv: Option<I420>,
    /// Inset sessions: where the previous picture's inset lay (`inset_packed::follow`).
    inset: Option<super::inset::InsetPlan>,
    /// The quantiser's range: quality while the picture is still, the target once it moves.
    guard: RateGuard,
    /// Each macroblock's threshold for the next frame, where the periphery is held
    /// (`encode::hold`), and the stream decoded as a client shows it, which held blocks repeat.
    hold: Option<Vec<u8>>,
    shown: Option<Shown>,
}

/// One encoded frame: Annex B NAL units.
#[derive(Debug, Clone)]
pub struct H264Frame {
    pub bytes: Vec<u8>,
    pub keyframe: bool,
}

impl std::fmt::Debug for H264Stream {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("H264Stream")
            .field("config", &self.config)
            .field("size", &self.size)
            .field("keyframe_asked", &self.keyframe_asked)
            .finish_non_exhaustive()
    }
}

impl H264Stream {
    pub fn new(config: H264Config) -> H264Stream {
        H264Stream {
            config,
            encoder: None,
            size: (0, 0),
            last_keyframe: None,
            last_check: 0,
            keyframe_asked: true,
            started: Instant::now(),
            last_ms: 0,
            yuv: None,
            inset: None,
            guard: RateGuard::default(),
            hold: None,
            shown: None,
        }
    }

    /// Where the previous picture's inset lay, for an inset session.
    pub fn held_inset(&self) -> Option<&super::inset::InsetPlan> {
        self.inset.as_ref()
    }

    /// Records where this picture's inset lies.
    pub fn hold_inset(&mut self, plan: super::inset::InsetPlan) {
        self.inset = Some(plan);
    }

    /// The next frame repeats what the client shows in each macroblock within its threshold
    /// (`encode::hold`; one threshold a block of the picture as encoded). A keyframe codes
    /// every block, and nothing is held until the stream's decoder has seen one.
    pub fn hold_next(&mut self, thresholds: Vec<u8>) {
        self.hold = Some(thresholds);
    }

    /// The next frame is a keyframe (a client's decoder failed, or it resized).
    pub fn ask_keyframe(&mut self) {
        self.keyframe_asked = true;
    }

    /// New settings apply from the next frame, which is a keyframe.
    pub fn reconfigure(&mut self, config: H264Config) {
        if config != self.config {
            self.config = config;
            self.encoder = None;
        }
    }

    /// Makes the encoder for this size and settings if there is none (a new one starts with a
    /// keyframe).
    fn ensure_encoder(&mut self, width: u32, height: u32) -> Result<(), EncodeError> {
        if self.size != (width, height) {
            self.encoder = None;
        }
        if self.encoder.is_none() {
            let config = EncoderConfig::new()
                .bitrate(BitRate::from_bps(self.config.kbps.saturating_mul(1000)))
                .max_frame_rate(FrameRate::from_hz(60.0))
                .rate_control_mode(RateControlMode::Bitrate)
                .usage_type(UsageType::CameraVideoRealTime)
                .profile(Profile::Baseline)
                .sps_pps_strategy(SpsPpsStrategy::ConstantId)
                .skip_frames(false)
                // With openh264's background detection on, a still camera's P-frames came out
                // 14 bytes long and never refined the keyframe (foveal FLIP 0.104 at
                // 4000 kbit/s); without it or adaptive quantisation, QP ≤ 22 reaches JPEG
                // q85's foveal FLIP in ~5 kB P-frames, and the guard frees the quantiser
                // where the picture moves too much for that (`rate_guard`).
                //
                // Below QP 18 openh264 never settles on a still picture: every P-frame re-codes
                // it (460 bytes a frame on `bunny-marble`, 2438 on `gallery` at 720p, 13–17
                // from QP 18 up), which is what `encode::hold` stops where the eye cannot
                // tell; the floor stays at 10, whose refinement the fovea needs (where the
                // target pays for it the whole quality range: `rate_guard::FINE_BITS_PER_PIXEL`).
                .qp(QpRange::new(
                    super::rate_guard::QpCap::MIN_QP,
                    self.guard.cap().max_qp(self.config.kbps, width, height),
                ))
                .background_detection(false)
                // Its scene-change detection sent a keyframe every 17 frames of a moving test
                // picture once the quantiser was free; keyframes come when due, when asked
                // for, and when the guard switches, and nowhere else.
                .scene_change_detect(false)
                .adaptive_quantization(false)
                .num_threads(1)
                // Full range, as `encode::yuv` converts: the decoder must know.
                .vui(VuiConfig::bt601().full_range(true));
            let mut encoder = Encoder::with_api_config(api()?, config)
                .map_err(|e| EncodeError::H264(e.to_string()))?;
            quiet(&mut encoder);
            self.encoder = Some(encoder);
            self.size = (width, height);
            self.keyframe_asked = true;
        }
        Ok(())
    }

    /// Encodes tightly packed RGBA8 pixels of even width and height, timed by the wall clock.
    pub fn encode(
        &mut self,
        rgba: &[u8],
        width: u32,
        height: u32,
    ) -> Result<H264Frame, EncodeError> {
        let ms = self.started.elapsed().as_millis() as u64;
        self.encode_at(rgba, width, height, ms)
    }

    /// Encodes a frame already converted to I420 (Y, U, V planes, tight; the renderer's
    /// `i420` readback), timed by the wall clock.
    pub fn encode_i420(
        &mut self,
        planes: &[u8],
        width: u32,
        height: u32,
    ) -> Result<H264Frame, EncodeError> {
        let ms = self.started.elapsed().as_millis() as u64;
        self.encode_picture(Picture::I420(planes), width, height, ms)
    }

    /// Encodes a frame shown `ms` after the stream's first. Rate control spends the bitrate
    /// over the time between frames, so frames at one timestamp would get almost no bits.
    pub fn encode_at(
        &mut self,
        rgba: &[u8],
        width: u32,
        height: u32,
        ms: u64,
    ) -> Result<H264Frame, EncodeError> {
        self.encode_picture(Picture::Rgba(rgba), width, height, ms)
    }

    fn encode_picture(
        &mut self,
        picture: Picture,
        width: u32,
        height: u32,
        ms: u64,
    ) -> Result<H264Frame, EncodeError> {
        if !width.is_multiple_of(2) || !height.is_multiple_of(2) || width == 0 || height == 0 {
            return Err(EncodeError::OddSize(width, height));
        }
        let (w, h) = (width as usize, height as usize);
        let (len, expected) = match picture {
            Picture::Rgba(p) => (p.len(), w * h * 4),
            Picture::I420(p) => (p.len(), w * h * 3 / 2),
        };
        if len != expected {
            return Err(EncodeError::Size {
                width,
                height,
                expected,
                got: len,
            });
        }
        // Strictly increasing, as rate control expects.
        let ms = ms.max(self.last_ms + 1);
        let since_last = ms - self.last_ms;
        self.last_ms = ms;
        let every = u64::try_from(self.config.keyframe_every.as_millis()).unwrap_or(u64::MAX);
        let due = self
            .last_keyframe
            .is_none_or(|t| ms.saturating_sub(t) >= every);
        // A keyframe sent anyway is a free check; else one every GUARD_CHECK_MS.
        let check =
            due || self.keyframe_asked || ms.saturating_sub(self.last_check) >= GUARD_CHECK_MS;
        if check {
            self.last_check = ms;
        }
        if let Switch::To(cap) = self.guard.decide(f64::from(self.config.kbps), check) {
            tracing::debug!(
                ?cap,
                kbps = self.config.kbps,
                "H.264 quantiser range switched"
            );
            self.encoder = None;
        }
        self.ensure_encoder(width, height)?;
        let ask = self.keyframe_asked || due;
        let hold = self.hold.take();
        self.take_picture(picture, w, h, hold.as_deref().filter(|_| !ask));
        let Some(encoder) = self.encoder.as_mut() else {
            return Err(EncodeError::H264("no encoder".into()));
        };
        if ask {
            encoder.force_intra_frame();
        }
        let Some(yuv) = self.yuv.as_ref() else {
            return Err(EncodeError::H264("no picture buffer".into()));
        };
        let stream = encoder
            .encode_at(yuv, Timestamp::from_millis(ms))
            .map_err(|e| EncodeError::H264(e.to_string()))?;
        // Only an IDR frame lets a decoder start (WebCodecs wants one after configure).
        let keyframe = stream.frame_type() == FrameType::IDR;
        let bytes = stream.to_vec();
        if bytes.is_empty() {
            // A skipped frame would leave the client waiting: skipping is off, so this is a fault.
            return Err(EncodeError::H264(format!(
                "the encoder returned no data ({:?})",
                stream.frame_type()
            )));
        }
        if keyframe {
            self.last_keyframe = Some(ms);
            self.keyframe_asked = false;
        }
        self.guard.record(bytes.len(), keyframe, since_last);
        // Decoded for the next frame's hold while the next frame renders (`encode::shown`); a
        // decoder starts at a keyframe, so until one comes nothing is held.
        if hold.is_none() || keyframe {
            self.shown = None;
        }
        if hold.is_some() {
            let shown = match &mut self.shown {
                Some(s) => Some(s),
                slot if keyframe => Some(slot.insert(Shown::start())),
                _ => None,
            };
            if let Some(s) = shown {
                s.submit(bytes.clone());
            }
        }
        Ok(H264Frame { bytes, keyframe })
    }

    /// Converts the frame into the stream's picture buffer and holds the blocks `hold` allows
    /// (not on a keyframe: the caller passes none).
    fn take_picture(&mut self, picture: Picture, w: usize, h: usize, hold: Option<&[u8]>) {
        // One YUV buffer per stream, refilled each frame (1.4 MB at 720p not reallocated).
        let yuv = match &mut self.yuv {
            Some(buffer) if buffer.dimensions() == (w, h) => buffer,
            slot => slot.insert(I420::new(w, h)),
        };
        match picture {
            Picture::Rgba(rgba) => yuv.fill(rgba),
            Picture::I420(planes) => yuv.copy_from(planes),
        }
        let shown = match hold {
            Some(_) => self.shown.as_mut().and_then(|s| s.picture()),
            None => None,
        };
        if let (Some(t), Some(shown)) = (hold, shown) {
            super::hold::merge(yuv, shown, t);
        }
    }
}
