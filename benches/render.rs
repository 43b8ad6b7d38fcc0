//! Renderer throughput benchmark (filled in with the renderer API).
fn main() {}
