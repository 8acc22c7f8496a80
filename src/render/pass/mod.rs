//! One file per pass, each beside its WGSL in `shaders/`, in frame order:
//! gbuffer → sampling → compact → shade → jfa → resolve → dof → output (with the gaze marker).

pub mod compact;
pub mod dof;
pub mod gbuffer;
pub mod jfa;
pub mod output;
pub mod resolve;
pub mod sampling;
pub mod shade;

/// Every shader the renderer ships, by file name, as compiled (with the shared prelude where
/// the pass uses it), for the naga validation test.
pub fn shaders() -> Vec<(&'static str, String)> {
    use crate::render::gpu::compose;
    vec![
        ("gbuffer.wgsl", compose(gbuffer::SHADER)),
        ("sampling.wgsl", compose(sampling::SHADER)),
        ("compact.wgsl", compose(compact::SHADER)),
        ("shade.wgsl", compose(shade::SHADER)),
        ("jfa.wgsl", compose(jfa::SHADER)),
        ("resolve.wgsl", compose(resolve::SHADER)),
        ("dof.wgsl", compose(dof::SHADER)),
        ("output.wgsl", compose(output::SHADER)),
        ("common.wgsl", crate::render::gpu::COMMON.to_string()),
    ]
}
