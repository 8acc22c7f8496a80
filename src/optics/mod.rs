//! CPU twins of the numbers the shaders compute. Each function here is what a shader does,
//! written plainly so tests can hold the GPU to it.

pub mod acuity;
pub mod coarse_gather;
pub mod color;
pub mod dipole;
pub mod dof;
pub mod lights;
pub mod saliency;
pub mod shading;
pub mod specular;
