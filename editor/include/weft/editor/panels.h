#pragma once
/// @file
/// The editor's ImGui panels (docs/editor.md, "Panels"). Called between ImGuiLayer::begin_frame
/// and end_frame, once per displayed frame, before the frame's steps: every change a panel makes
/// (a widget, or a pending value from a script or a key) applies at the next step.
#include <string>
#include <vector>

#include "weft/editor/session.h"

namespace weft::editor {

struct PanelLayout {
    float width = 0.0F, height = 0.0F;  ///< the window's size in ImGui units (screen pixels)
    double fps = 0.0;                   ///< displayed frames per second (measured by the caller)
    /// The Scenes panel's list (names in the scene folder); a click asks to open one.
    const std::vector<std::string>* scenes = nullptr;
};

/// The left column (play controls, scenes, solver, materials, collision, world), the stats column on the
/// right, and a red banner at the top while the last step did not converge or met NaN.
void draw_panels(Session& session, const PanelLayout& layout);

}  // namespace weft::editor
