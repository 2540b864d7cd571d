#pragma once
/// @file
/// A cloth's `Material` converted to what the element math evaluates (backend kit).

#include "weft/material.h"
#include "weft/physics/implicit_terms.h"
#include "weft/physics/membrane.h"

namespace weft {

/// A cloth's material in the terms the solvers evaluate, in scalar T: Lamé parameters instead of
/// stiffness and Poisson ratio, everything else as given. Backends convert once per cloth per substep.
template <typename T>
using MaterialTerms = physics::MaterialCoefficients<T>;

template <typename T>
[[nodiscard]] MaterialTerms<T> material_terms(const Material& m) {
    MaterialTerms<T> p;
    p.membrane = physics::membrane_material(static_cast<T>(m.stretch_stiffness), static_cast<T>(m.poisson_ratio));
    p.bending = static_cast<T>(m.bending_stiffness);
    p.damping_mass = static_cast<T>(m.damping_mass);
    p.damping_stiffness = static_cast<T>(m.damping_stiffness);
    p.drag = static_cast<T>(m.drag_coefficient);
    p.lift = static_cast<T>(m.lift_coefficient);
    p.thickness = static_cast<T>(m.contact_thickness);
    p.friction = static_cast<T>(m.friction);
    return p;
}

}  // namespace weft
