use serde::de::DeserializeOwned;
use serde_json::{Map, Value};

use super::{Ack, CameraMove, ErrorCode, Gaze, Hello, Limits, ProtocolError, PROTOCOL_VERSION};
use crate::settings::{KnobError, SettingsPatch};

/// A client message that parsed and passed every range check.
#[derive(Debug, Clone, PartialEq)]
pub enum ClientMessage {
    Hello(Hello),
    Gaze(Gaze),
    Ack(Ack),
    Settings(SettingsPatch),
    Camera(CameraMove),
    /// The next H.264 frame should be a keyframe (the client's decoder failed or restarted).
    Keyframe,
}

/// Parses and validates one text message. Scene and preset names are checked by the session,
/// which knows what exists; everything that can be judged from the message alone is judged here.
pub fn parse_client_message(text: &str, limits: &Limits) -> Result<ClientMessage, ProtocolError> {
    if text.len() > limits.max_message_bytes {
        return Err(ProtocolError::new(
            ErrorCode::TooLarge,
            format!(
                "message is {} bytes; the limit is {} bytes",
                text.len(),
                limits.max_message_bytes
            ),
        ));
    }
    let value: Value = serde_json::from_str(text).map_err(|e| json_error(text, &e))?;
    let Value::Object(mut map) = value else {
        return Err(ProtocolError::new(
            ErrorCode::BadJson,
            "a message must be a JSON object",
        ));
    };
    let kind =
        match map.remove("type") {
            Some(Value::String(kind)) => kind,
            Some(_) => {
                return Err(ProtocolError::new(
                    ErrorCode::MissingType,
                    "`type` must be a string",
                ))
            }
            None => return Err(ProtocolError::new(
                ErrorCode::MissingType,
                "message has no `type` (expected hello, gaze, ack, settings, camera or keyframe)",
            )),
        };
    match kind.as_str() {
        "hello" => {
            let hello: Hello = fields(map, "hello")?;
            validate_hello(&hello, limits)?;
            Ok(ClientMessage::Hello(hello))
        }
        "gaze" => {
            let gaze: Gaze = fields(map, "gaze")?;
            validate_gaze(&gaze, limits)?;
            Ok(ClientMessage::Gaze(gaze))
        }
        "ack" => {
            let ack: Ack = fields(map, "ack")?;
            if let Some(t) = ack.t_ms {
                finite("ack.t_ms", t)?;
            }
            Ok(ClientMessage::Ack(ack))
        }
        "settings" => {
            let patch: SettingsPatch = fields(map, "settings")?;
            validate_settings(&patch)?;
            Ok(ClientMessage::Settings(patch))
        }
        "camera" => {
            let m: CameraMove = fields(map, "camera")?;
            validate_camera(&m)?;
            Ok(ClientMessage::Camera(m))
        }
        "keyframe" => {
            let _: NoFields = fields(map, "keyframe")?;
            Ok(ClientMessage::Keyframe)
        }
        other => Err(ProtocolError::new(
            ErrorCode::UnknownType,
            format!(
                "unknown message type {other:?} (expected hello, gaze, ack, settings, camera or keyframe)"
            ),
        )),
    }
}

/// A message with nothing but its type.
#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct NoFields {}

fn fields<T: DeserializeOwned>(map: Map<String, Value>, kind: &str) -> Result<T, ProtocolError> {
    serde_json::from_value(Value::Object(map))
        .map_err(|e| ProtocolError::new(ErrorCode::BadField, format!("{kind}: {e}")))
}

/// serde_json rejects `NaN` and `Infinity` as syntax errors; name them, since they are the
/// commonest way a tracker's invalid sample reaches us (Python's json.dumps writes them).
fn json_error(text: &str, e: &serde_json::Error) -> ProtocolError {
    let line = text.lines().nth(e.line().saturating_sub(1)).unwrap_or("");
    let at = line
        .char_indices()
        .nth(e.column().saturating_sub(1))
        .map(|(i, _)| i)
        .unwrap_or(0);
    let rest = line.get(at..).unwrap_or("");
    let rest = rest.trim_start_matches(['-', '+']);
    if rest.starts_with("NaN") || rest.starts_with("Infinity") || rest.starts_with("inf") {
        return ProtocolError::new(
            ErrorCode::NotFinite,
            "NaN and Infinity are not valid in a message; send finite numbers (drop invalid samples)",
        );
    }
    if e.to_string().contains("number out of range") {
        return ProtocolError::new(ErrorCode::NotFinite, format!("number out of range: {e}"));
    }
    ProtocolError::new(ErrorCode::BadJson, format!("not valid JSON: {e}"))
}

fn finite(name: &str, v: f64) -> Result<f64, ProtocolError> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(ProtocolError::new(
            ErrorCode::NotFinite,
            format!("{name} must be finite, got {v}"),
        ))
    }
}

fn in_range(name: &str, v: f64, lo: f64, hi: f64) -> Result<(), ProtocolError> {
    finite(name, v)?;
    if v < lo || v > hi {
        return Err(ProtocolError::new(
            ErrorCode::OutOfRange,
            format!("{name} = {v} is outside [{lo}, {hi}]"),
        ));
    }
    Ok(())
}

fn validate_hello(h: &Hello, limits: &Limits) -> Result<(), ProtocolError> {
    if h.v != PROTOCOL_VERSION {
        return Err(ProtocolError::new(
            ErrorCode::UnsupportedVersion,
            format!(
                "protocol version {} is not supported; this server speaks v{PROTOCOL_VERSION}",
                h.v
            ),
        ));
    }
    if h.width == 0 || h.height == 0 || h.width > limits.max_width || h.height > limits.max_height {
        return Err(ProtocolError::new(
            ErrorCode::OutOfRange,
            format!(
                "frame size {}x{} is outside 1x1 ..= {}x{}",
                h.width, h.height, limits.max_width, limits.max_height
            ),
        ));
    }
    in_range("display.width_cm", h.display.width_cm, 1.0, 1000.0)?;
    in_range("display.distance_cm", h.display.distance_cm, 1.0, 10_000.0)?;
    in_range("quality", f64::from(h.quality), 1.0, 100.0)?;
    if let Some(k) = h.bitrate_kbps {
        let (lo, hi) = crate::encode::h264::KBPS_RANGE;
        in_range("bitrate_kbps", f64::from(k), f64::from(lo), f64::from(hi))?;
    }
    if let Some(s) = h.keyframe_s {
        let (lo, hi) = crate::encode::h264::KEYFRAME_S_RANGE;
        in_range("keyframe_s", s, lo, hi)?;
    }
    if let Some(d) = h.inset_deg {
        let (lo, hi) = crate::encode::inset::INSET_DEG_RANGE;
        in_range("inset_deg", d, lo, hi)?;
    }
    if h.codec == super::Codec::H264 && (!h.width.is_multiple_of(2) || !h.height.is_multiple_of(2))
    {
        return Err(ProtocolError::new(
            ErrorCode::OutOfRange,
            format!(
                "h264 frames need an even width and height (4:2:0 chroma), got {}x{}",
                h.width, h.height
            ),
        ));
    }
    in_range(
        "max_in_flight",
        f64::from(h.max_in_flight),
        1.0,
        f64::from(limits.max_in_flight),
    )?;
    Ok(())
}

fn validate_camera(m: &CameraMove) -> Result<(), ProtocolError> {
    let within = |name: &str, v: f64, lo: f64, hi: f64| {
        finite(name, v)?;
        if (lo..=hi).contains(&v) {
            Ok(())
        } else {
            Err(ProtocolError::new(
                ErrorCode::OutOfRange,
                format!("camera.{name} = {v} is outside [{lo}, {hi}]"),
            ))
        }
    };
    if let Some(p) = &m.pose {
        for v in p.eye.iter().chain(&p.target).chain(p.up.iter().flatten()) {
            within("pose", *v, -1e6, 1e6)?;
        }
    }
    for v in m.orbit_deg.iter().flatten() {
        within("orbit_deg", *v, -360.0, 360.0)?;
    }
    for v in m.pan.iter().flatten() {
        within("pan", *v, -10.0, 10.0)?;
    }
    if let Some(d) = m.dolly {
        within("dolly", d, 0.05, 20.0)?;
    }
    Ok(())
}

fn validate_settings(p: &SettingsPatch) -> Result<(), ProtocolError> {
    p.validate().map_err(ProtocolError::from)
}

impl From<KnobError> for ProtocolError {
    fn from(e: KnobError) -> Self {
        let code = match e {
            KnobError::NotFinite { .. } => ErrorCode::NotFinite,
            KnobError::OutOfRange { .. } => ErrorCode::OutOfRange,
            KnobError::UnknownPreset(_) => ErrorCode::UnknownPreset,
        };
        ProtocolError::new(code, e.to_string())
    }
}

fn validate_gaze(g: &Gaze, limits: &Limits) -> Result<(), ProtocolError> {
    finite("gaze.t_ms", g.t_ms)?;
    if let Some(t) = g.sample_t_ms {
        finite("gaze.sample_t_ms", t)?;
    }
    in_range("gaze.x", g.x, limits.gaze[0], limits.gaze[1])?;
    in_range("gaze.y", g.y, limits.gaze[0], limits.gaze[1])?;
    if let Some(p) = g.pupil_mm {
        in_range("gaze.pupil_mm", p, limits.pupil_mm[0], limits.pupil_mm[1])?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn code(text: &str) -> ErrorCode {
        match parse_client_message(text, &Limits::default()) {
            Ok(m) => panic!("expected an error for {text}, got {m:?}"),
            Err(e) => e.code,
        }
    }

    #[test]
    fn hello_defaults_fill_every_omitted_field() {
        let m = parse_client_message(r#"{"type":"hello"}"#, &Limits::default()).unwrap();
        assert_eq!(m, ClientMessage::Hello(Hello::default()));
    }

    #[test]
    fn gaze_round_trips_through_json() {
        let g = Gaze {
            seq: 17,
            t_ms: 12345.5,
            x: 0.25,
            y: 1.0,
            pupil_mm: Some(3.8),
            sample_t_ms: None,
        };
        let mut v = serde_json::to_value(g).unwrap();
        v["type"] = "gaze".into();
        let m = parse_client_message(&v.to_string(), &Limits::default()).unwrap();
        assert_eq!(m, ClientMessage::Gaze(g));
    }

    #[test]
    fn every_bad_input_gets_its_own_code() {
        assert_eq!(code("not json"), ErrorCode::BadJson);
        assert_eq!(code("[1,2]"), ErrorCode::BadJson);
        assert_eq!(code(r#"{"seq":1}"#), ErrorCode::MissingType);
        assert_eq!(code(r#"{"type":5}"#), ErrorCode::MissingType);
        assert_eq!(code(r#"{"type":"teleport"}"#), ErrorCode::UnknownType);
        assert_eq!(
            code(r#"{"type":"gaze","seq":1,"t_ms":0,"x":0.5}"#),
            ErrorCode::BadField
        );
        assert_eq!(
            code(r#"{"type":"gaze","seq":1,"t_ms":0,"x":0.5,"y":null}"#),
            ErrorCode::BadField
        );
        assert_eq!(code(r#"{"type":"hello","widht":64}"#), ErrorCode::BadField);
        assert_eq!(
            code(r#"{"type":"gaze","seq":1,"t_ms":0,"x":NaN,"y":0.5}"#),
            ErrorCode::NotFinite
        );
        assert_eq!(
            code(r#"{"type":"gaze","seq":1,"t_ms":0,"x":-Infinity,"y":0.5}"#),
            ErrorCode::NotFinite
        );
        assert_eq!(
            code(r#"{"type":"gaze","seq":1,"t_ms":0,"x":1e999,"y":0.5}"#),
            ErrorCode::NotFinite
        );
        assert_eq!(
            code(r#"{"type":"gaze","seq":1,"t_ms":0,"x":1.01,"y":0.5}"#),
            ErrorCode::OutOfRange
        );
        assert_eq!(
            code(r#"{"type":"gaze","seq":1,"t_ms":0,"x":0.5,"y":-0.001}"#),
            ErrorCode::OutOfRange
        );
        assert_eq!(
            code(r#"{"type":"gaze","seq":1,"t_ms":0,"x":0.5,"y":0.5,"pupil_mm":0.5}"#),
            ErrorCode::OutOfRange
        );
        assert_eq!(code(r#"{"type":"hello","width":0}"#), ErrorCode::OutOfRange);
        assert_eq!(
            code(r#"{"type":"hello","width":100000,"height":10}"#),
            ErrorCode::OutOfRange
        );
        assert_eq!(
            code(r#"{"type":"hello","max_in_flight":0}"#),
            ErrorCode::OutOfRange
        );
        assert_eq!(
            code(r#"{"type":"hello","v":2}"#),
            ErrorCode::UnsupportedVersion
        );
        assert_eq!(
            code(r#"{"type":"hello","codec":"gif"}"#),
            ErrorCode::BadField
        );
        let big = format!(r#"{{"type":"hello","scene":"{}"}}"#, "a".repeat(5000));
        assert_eq!(code(&big), ErrorCode::TooLarge);
    }

    #[test]
    fn camera_moves_parse_and_out_of_range_ones_are_refused() {
        let l = Limits::default();
        let m = parse_client_message(r#"{"type":"camera","orbit_deg":[10,-5],"dolly":0.5}"#, &l);
        assert!(
            matches!(m, Ok(ClientMessage::Camera(c)) if c.orbit_deg == Some([10.0, -5.0]) && c.dolly == Some(0.5))
        );
        for bad in [
            r#"{"type":"camera","dolly":0}"#,
            r#"{"type":"camera","orbit_deg":[1000,0]}"#,
            r#"{"type":"camera","pan":[0,11]}"#,
            r#"{"type":"camera","pose":{"eye":[1e9,0,0],"target":[0,0,0]}}"#,
        ] {
            let e = parse_client_message(bad, &l).unwrap_err();
            assert_eq!(e.code, ErrorCode::OutOfRange, "{bad}");
        }
        let e = parse_client_message(r#"{"type":"camera","zoom":2}"#, &l).unwrap_err();
        assert_eq!(e.code, ErrorCode::BadField);
    }

    #[test]
    fn gaze_on_the_exact_border_is_valid() {
        for (x, y) in [(0.0, 0.0), (1.0, 1.0), (0.0, 1.0), (1.0, 0.0)] {
            let text =
                format!(r#"{{"type":"gaze","seq":3,"t_ms":1.5,"x":{x},"y":{y},"pupil_mm":10}}"#);
            assert!(
                parse_client_message(&text, &Limits::default()).is_ok(),
                "{text}"
            );
        }
    }
}
