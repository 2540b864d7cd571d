#pragma once
/// @file
/// Cloth material: the physical constants of one cloth instance.

namespace weft {

/// Material of a cloth. Defaults describe a light cotton-like fabric.
struct Material {
    /// Stretch stiffness: Young's modulus × fabric thickness, N/m. Valid range [1, 1e8].
    double stretch_stiffness = 5.0e3;
    /// Poisson ratio of the membrane, dimensionless. Valid range [0, 0.49].
    double poisson_ratio = 0.3;
    /// Bending stiffness of the discrete hinges, N·m. Valid range [0, 1].
    double bending_stiffness = 1.0e-5;
    /// Rayleigh damping, mass-proportional part α, 1/s (f = −α M v). Valid range [0, 100].
    double damping_mass = 0.0;
    /// Rayleigh damping, stiffness-proportional part β, s (f = −β K v). Valid range [0, 1].
    double damping_stiffness = 1.0e-3;
    /// Aerodynamic drag coefficient (normal to the surface), dimensionless. Valid range [0, 10].
    double drag_coefficient = 1.0;
    /// Aerodynamic lift coefficient, dimensionless. Valid range [0, 10].
    double lift_coefficient = 0.3;
    /// Contact thickness: the distance kept from colliders, m. Valid range [1e-5, 0.1].
    double contact_thickness = 5.0e-3;
    /// Coulomb friction coefficient against colliders, dimensionless. Valid range [0, 10].
    double friction = 0.3;
};

}  // namespace weft
