//! glTF 2.0 (`.glb`, or `.gltf` with its buffers): the meshes of its node tree, and the photos
//! its materials carry.

pub mod mesh;
pub mod texture;
