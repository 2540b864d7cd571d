#pragma once
/// @file
/// Cloth material: the physical constants of one cloth instance. Valid ranges: the parameter table
/// (weft/parameters.h; `weft help scene-keys`), which `World::add_cloth` checks.

#include "weft/physics/membrane.h"

namespace weft {

/// Material of a cloth. Defaults describe a light cotton-like fabric.
struct Material {
    /// Stretch stiffness: Young's modulus × fabric thickness, N/m.
    double stretch_stiffness = 5.0e3;
    /// Poisson ratio of the membrane, dimensionless.
    double poisson_ratio = 0.3;
    /// Bending stiffness of the discrete hinges, N·m.
    double bending_stiffness = 1.0e-5;
    /// Rayleigh damping, mass-proportional part α, 1/s (f = −α M v).
    double damping_mass = 0.0;
    /// Rayleigh damping, stiffness-proportional part β, s (f = −β K v).
    double damping_stiffness = 1.0e-3;
    /// Aerodynamic drag coefficient (normal to the surface), dimensionless.
    double drag_coefficient = 1.0;
    /// Aerodynamic lift coefficient, dimensionless.
    double lift_coefficient = 0.3;
    /// Contact thickness: the distance kept from colliders, m.
    double contact_thickness = 5.0e-3;
    /// Coulomb friction coefficient against colliders, dimensionless.
    double friction = 0.3;
};

/// A cloth's material in the terms the solvers evaluate, in scalar T: Lamé parameters instead of
/// stiffness and Poisson ratio, everything else as given. Backends convert once per cloth per substep.
template <typename T>
struct MaterialTerms {
    physics::MembraneMaterial<T> membrane{};
    T bending{}, damping_mass{}, damping_stiffness{};
    T drag{}, lift{}, thickness{}, friction{};
};

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
