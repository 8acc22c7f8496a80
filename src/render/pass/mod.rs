//! One file per pass, each beside its WGSL in `shaders/`, in frame order:
//! (photons → pyramid, once per static scene) → gbuffer → (screen_diffusion) → sampling →
//! compact → shade → jfa → resolve → dof → output (with the gaze marker).

pub mod compact;
pub mod dof;
pub mod gbuffer;
pub mod jfa;
pub mod output;
pub mod photons;
pub mod resolve;
pub mod sampling;
pub mod screen_diffusion;
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
        ("photons.wgsl", compose(photons::PHOTON_SHADER)),
        ("pyramid.wgsl", compose(photons::PYRAMID_SHADER)),
        ("screen_diffusion.wgsl", compose(screen_diffusion::SHADER)),
        ("common.wgsl", crate::render::gpu::COMMON.to_string()),
    ]
}
