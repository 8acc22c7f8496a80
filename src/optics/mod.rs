//! CPU twins of the numbers the shaders compute. Each function here is what a shader does,
//! written plainly so tests can hold the GPU to it.

pub mod color;
pub mod shading;
pub mod acuity;
pub mod saliency;
pub mod dipole;
