#pragma once
/// @file
/// Cloth material: the physical constants of one cloth instance. Valid ranges: the parameter table
/// (weft/parameters.h; `weft help scene-keys`), which `World::add_cloth` checks.

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

}  // namespace weft
