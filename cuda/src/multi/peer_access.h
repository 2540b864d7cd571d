#pragma once
/// @file
/// Peer access between two CUDA devices for the multi-GPU solve (docs/multi-gpu.md): kernels on one
/// device store into the other's memory over NVLink.

namespace weft::cuda::multi {

/// Makes `device` able to read and write `peer`'s memory, once per pair in the process (enabling a
/// pair twice is an error the runtime reports). Nothing for device == peer. Throws weft::Error naming
/// the pair when the devices cannot reach each other. Leaves `device` current.
void enable_peer_access(int device, int peer);

}  // namespace weft::cuda::multi
