#pragma once
/// @file
/// How the simulated cloth reaches a renderer each display frame (docs/rendering.md, "The frame
/// pipeline"). Zero-copy where the world's backend can write the renderer's exported cloth slots
/// (the CUDA backend and a Vulkan device on the same GPU, matched by UUID); a host upload otherwise,
/// with the reason kept. Either way a display frame is
///
///     RenderFrame f = feed.simulate([&] { loop.advance(wall_seconds); });  // fills the next slot
///     renderer.submit(f);   // or window.present(f): drawn without a host wait
///     ... the next frame's simulate() runs here, while the GPU draws f ...
///
/// so the simulation of frame N+1 overlaps the drawing of frame N. On the zero-copy path the two
/// use different slots (double buffering) and each slot's timeline semaphore orders its writer and
/// reader on the GPU: the backend's work for frame N+2 waits for the draw of frame N, never the host.
/// Every frame carries a stamp (its number) that the writer stores before and after the vertices,
/// and the renderer reads back after drawing: check() counts frames that did not see one whole state.
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "weft/backend/interop.h"
#include "weft/render/render_scene.h"
#include "weft/render/renderer.h"
#include "weft/world.h"

namespace weft::render {

class ClothFeed {
public:
    struct Options {
        bool zero_copy = true;  ///< false: always the host upload (for comparisons)
    };

    /// Links `world` (its backend) to `renderer`, which must have loaded `scene` (kept by
    /// reference, with the world and the renderer, for the feed's life). Throws weft::Error only
    /// for failures of an import that should have worked; an unavailable path is a fallback.
    ClothFeed(World& world, Renderer& renderer, const RenderScene& scene, Options options);
    ClothFeed(World& world, Renderer& renderer, const RenderScene& scene) : ClothFeed(world, renderer, scene, Options{}) {}
    ~ClothFeed();
    ClothFeed(const ClothFeed&) = delete;
    ClothFeed& operator=(const ClothFeed&) = delete;

    /// The backend writes the renderer's slots.
    [[nodiscard]] bool zero_copy() const { return output_ != nullptr; }
    /// Why the host upload is used ("" on the zero-copy path).
    [[nodiscard]] const std::string& fallback_reason() const { return why_; }
    /// "interop (zero-copy, 2 slots)" or "host upload (REASON)".
    [[nodiscard]] std::string describe() const;

    /// Runs `steps` (the frame's simulation: FrameLoop::advance, edits, nothing) with the backend
    /// writing the next slot, and returns the frame that draws the result. The frame must be drawn
    /// (Renderer::submit, Window::present) or skipped (Renderer::skip_frame) before the next call;
    /// its host vertices (upload path) stay valid until then.
    [[nodiscard]] RenderFrame simulate(const std::function<void()>& steps);

    /// After `frame` was drawn and its transfer() is known (Renderer::collect, or the window's next
    /// present): whether it read exactly its own state, counted in torn_frames() when not.
    bool check(const RenderFrame& frame, const TransferStats& drawn);
    [[nodiscard]] std::int64_t frames() const { return frames_; }
    [[nodiscard]] std::int64_t checked_frames() const { return checked_; }
    [[nodiscard]] std::int64_t torn_frames() const { return torn_; }

private:
    World& world_;
    Renderer& renderer_;
    const RenderScene& scene_;
    std::function<void()> make_current_;  ///< ClothInterop::make_current (GL slots), else empty
    std::unique_ptr<SharedOutput> output_;
    std::string why_;
    std::vector<std::uint64_t> values_;  ///< per slot: the last timeline value asked for
    std::vector<RenderVertex> vertices_;  ///< the upload path's frame
    std::vector<RenderVertex> collider_vertices_;  ///< the deforming colliders' vertices of the frame
    std::int64_t frames_ = 0, checked_ = 0, torn_ = 0;
};

}  // namespace weft::render
