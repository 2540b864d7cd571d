// The frame pipeline's link between a world and a renderer (see weft/render/cloth_feed.h).
//
// Slot timelines. Slot s's semaphore counts every access to it in order: the writer waits for the
// value the last draw of s signals, writes, signals the next value; the draw waits for that one and
// signals the next. values_[s] is the last value asked for, so the two never reuse or reorder a
// value (a timeline only moves up), whether or not steps ran in the frame.
#include "weft/render/cloth_feed.h"

#include "weft/error.h"

namespace weft::render {

ClothFeed::ClothFeed(World& world, Renderer& renderer, const RenderScene& scene, Options options)
    : world_(world), renderer_(renderer), scene_(scene) {
    if (!options.zero_copy) {
        why_ = "zero-copy switched off";
        return;
    }
    if (scene.cloth_vertices == 0) {
        why_ = "the scene has no cloth";
        return;
    }
    std::string why;
    std::optional<ClothInterop> link = renderer.export_cloth(why);
    if (!link) {
        why_ = std::string(renderer.name()) + ": " + why;
        return;
    }
    make_current_ = std::move(link->make_current);
    if (make_current_) make_current_();
    output_ = share_output(world, link->slots, link->device_uuid, why);
    if (!output_) {
        why_ = why;
        return;
    }
    values_ = link->timeline_values;
}

ClothFeed::~ClothFeed() {
    // A GL writer lets its buffers go through the context that owns them.
    if (output_ && make_current_) {
        try {
            make_current_();
        } catch (...) {  // NOLINT(bugprone-empty-catch): a destructor must not throw; the release goes on
        }
    }
    output_.reset();
}

std::string ClothFeed::describe() const {
    if (output_) return "interop (zero-copy, " + std::to_string(output_->slots()) + " slots)";
    return "host upload (" + why_ + ")";
}

RenderFrame ClothFeed::simulate(const std::function<void()>& steps) {
    RenderFrame frame;
    frame.stamp = static_cast<std::uint64_t>(++frames_);
    if (output_) {
        // Frames alternate between the slots: this one's writes never touch the slot the frame
        // before is being drawn from.
        const int slot = static_cast<int>((frames_ - 1) % output_->slots());
        std::uint64_t& value = values_[static_cast<std::size_t>(slot)];
        if (make_current_) make_current_();
        output_->begin_frame(slot, value, frame.stamp);
        try {
            if (steps) steps();
        } catch (...) {
            if (make_current_) make_current_();
            output_->end_frame(++value);  // the slot's next draw may still come; keep the count right
            throw;
        }
        if (make_current_) make_current_();  // the steps may have drawn with another context
        output_->end_frame(++value);
        frame.cloth_slot = slot;
        frame.wait_value = value;
        frame.signal_value = ++value;
    } else {
        if (steps) steps();
        cloth_vertices(world_, scene_, vertices_);
        frame.cloth = vertices_;
    }
    frame.collider_models = collider_models(scene_, world_.model(), world_.time());
    if (scene_.deforming_vertices > 0) {
        deforming_collider_vertices(scene_, world_.model(), world_.time(), collider_vertices_);
        frame.collider_vertices = collider_vertices_;
    }
    return frame;
}

bool ClothFeed::check(const RenderFrame& frame, const TransferStats& drawn) {
    ++checked_;
    const bool intact = frame_intact(drawn, frame.stamp);
    if (!intact) ++torn_;
    return intact;
}

}  // namespace weft::render
