// The bending models per triangle on the device (solver.bending = "shell" and "midedge";
// weft/physics/shell_bending_slots.h): pass 1, each triangle's terms at the Newton iteration's
// linearisation point, before the assembly, which reads them through each hinge's slots
// (element_terms.cuh: shell_hinge_terms). The same two passes as the CPU backend, in float.
#include "cuda_check.h"
#include "device_math.cuh"
#include "kernels.h"
#include "shell_bending_state.cuh"

namespace weft::cuda {
namespace {

__global__ void shell_faces_kernel(DeviceView d) {
    const std::uint32_t t = blockIdx.x * blockDim.x + threadIdx.x;
    if (t >= d.triangles) return;
    const StepParams& sp = step_params(d);
    const ClothParams& p = staged<ClothParams>(d, sp.cloth_offset)[d.triangle_cloth[t]];
    physics::ShellFaceTerms<float> out;
    if (p.bending > 0.0f) {
        const float h = sp.h;
        ShellFaceInput in;
        load_shell_face(d, t, in);
        V3 x[3][4], vk[3][4], dvw[3][4];
        for (int k = 0; k < 3; ++k)
            for (int a = 0; a < 4; ++a) {
                x[k][a] = vk[k][a] = dvw[k][a] = V3{};
                if (in.hinge[k] < 0) continue;
                const std::uint32_t v = in.vertex[k][a];
                const V3 w = load3(d.wk, v, d.n);
                x[k][a] = load3(d.x0, v, d.n) + h * w;  // the linearisation point x0 + h·w_k, as the CPU's
                vk[k][a] = load3(d.vk, v, d.n);
                dvw[k][a] = vk[k][a] - w;
            }
        if (d.midedge.xi != nullptr) {  // the mid-edge model: its normals were relaxed just before
            const physics::ShellReading<float> reading = midedge_reading_of(d, t);
            out = physics::shell_face_terms<float>(h, p.bending, p.damping_stiffness, in.rest, in.hinge, x, vk, dvw, in.rest_angle,
                                                   &reading);
        } else {
            out = physics::shell_face_terms<float>(h, p.bending, p.damping_stiffness, in.rest, in.hinge, x, vk, dvw,
                                                   in.rest_angle);
        }
    }
    d.shell_faces[t] = out;
}

}  // namespace

void launch_shell_faces(const DeviceView& d, cudaStream_t stream) {
    if (d.shell_faces == nullptr || d.triangles == 0) return;
    // The mid-edge model's normals at the same linearisation point first (midedge_kernels.cu).
    if (d.midedge.xi != nullptr) launch_midedge_relax(d, MidEdgeAt::Linearisation, stream);
    shell_faces_kernel<<<grid_for(d.triangles), kBlockSize, 0, stream>>>(d);
    WEFT_CUDA_CHECK_LAUNCH("shell_faces_kernel");
}

}  // namespace weft::cuda
