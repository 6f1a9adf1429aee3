//! The readers of the files a scene names, one folder per format family: meshes (OBJ with its
//! material library, PLY ASCII and binary, glTF 2.0, VRML97), luminaires' photometric files
//! (IES LM-63, EULUMDAT). Each turns bytes into the scene model's types and refuses a malformed
//! file with the file, the place and the fix; none reads a file itself (the loader hands each its
//! bytes through `Assets`). Photos (PNG, JPEG) are decoded by `crate::texture`, into the type a
//! mesh's part carries.

pub mod gltf;
pub mod obj;
pub mod photometric;
pub mod ply;
pub mod vrml;
