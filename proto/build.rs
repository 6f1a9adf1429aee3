//! Compiles `proto/restauro.proto` with protox, a protobuf compiler in Rust, so a fresh machine
//! needs no `protoc` (see ../shared/notes/api-notes.md, §1).

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let files = protox::compile(["proto/restauro.proto"], ["proto"])?;
    // The descriptors, for gRPC reflection (`grpcurl list` without the .proto file).
    let out = std::path::PathBuf::from(std::env::var("OUT_DIR")?);
    std::fs::write(out.join("restauro_descriptor.bin"), prost::Message::encode_to_vec(&files))?;
    tonic_prost_build::configure().build_server(true).build_client(true).compile_fds(files)?;
    println!("cargo:rerun-if-changed=proto");
    Ok(())
}
