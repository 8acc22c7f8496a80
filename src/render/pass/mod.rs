//! One file per pass, each beside its WGSL in `shaders/`, in frame order.

pub mod forward;
pub mod marker;

/// Every shader the renderer ships, by file name, for the naga validation test.
pub const SHADERS: &[(&str, &str)] = &[
    ("forward.wgsl", forward::SHADER),
    ("marker.wgsl", marker::SHADER),
];
