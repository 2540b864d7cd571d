#pragma once
/// @file
/// The editor's presets are the runtime's (weft/presets.h): its Solver and Materials menus.
#include "weft/presets.h"

namespace weft::editor {
using weft::find_preset;
using weft::material_presets;
using weft::Preset;
using weft::preset_names;
using weft::solver_presets;
}  // namespace weft::editor
