#pragma once
// Random geometry shared by the collision tests and the collision benchmark: triangle soups that
// stress the spatial hash, and smooth displacement fields that crumple and fold sheets.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <numbers>
#include <random>
#include <vector>

#include "weft/types.h"

namespace weft::test {

/// Start and end positions of a random triangle soup, and its triangles.
struct RandomSoup {
    std::vector<Vec3d> x0, x1;
    std::vector<Triangle> triangles;
};

/// Triangles between random neighbours of a jittered L³ lattice (spacing 1), so that many share
/// vertices and edges; every vertex moves by a normal step of `motion` per axis, and a fraction
/// `outliers` jump by up to 30 (bounds far larger than a hash cell: the oversized path). Draws from
/// `rng`, which the caller may go on using.
inline RandomSoup random_soup(std::mt19937& rng, int lattice, std::size_t triangles, double motion, double outliers) {
    std::uniform_real_distribution<double> jitter(-0.3, 0.3), unit(0.0, 1.0), jump(-30.0, 30.0);
    std::normal_distribution<double> step(0.0, 1.0);
    std::uniform_int_distribution<int> pick(0, lattice - 1), offset(-1, 1);
    RandomSoup s;
    const auto id = [&](int i, int j, int k) { return static_cast<std::uint32_t>((k * lattice + j) * lattice + i); };
    for (int k = 0; k < lattice; ++k)
        for (int j = 0; j < lattice; ++j)
            for (int i = 0; i < lattice; ++i) s.x0.push_back({i + jitter(rng), j + jitter(rng), k + jitter(rng)});
    for (const Vec3d& p : s.x0) {
        Vec3d d{motion * step(rng), motion * step(rng), motion * step(rng)};
        if (unit(rng) < outliers) d = {jump(rng), jump(rng), jump(rng)};
        s.x1.push_back(p + d);
    }
    while (s.triangles.size() < triangles) {
        const int i = pick(rng), j = pick(rng), k = pick(rng);
        std::uint32_t v[3] = {id(i, j, k), 0, 0};
        for (int c = 1; c < 3; ++c) {
            const int a = std::clamp(i + offset(rng), 0, lattice - 1), b = std::clamp(j + offset(rng), 0, lattice - 1),
                      d = std::clamp(k + offset(rng), 0, lattice - 1);
            v[c] = id(a, b, d);
        }
        if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2]) continue;
        s.triangles.push_back({{v[0], v[1], v[2]}});
    }
    return s;
}

/// A smooth random displacement field over the (x, y) plane: `count` sinusoids with wavelengths
/// uniform in [min_wavelength, max_wavelength] (m), random directions and phases, and amplitudes up
/// to `amplitude` (m) per coordinate.
struct SmoothField {
    struct Wave {
        double kx, ky, phase, amp[3];
    };
    std::vector<Wave> waves;
    SmoothField(std::mt19937& rng, double amplitude, double min_wavelength, double max_wavelength, int count = 4) {
        constexpr double kTwoPi = 2.0 * std::numbers::pi;
        std::uniform_real_distribution<double> unit(0.0, 1.0);
        for (int i = 0; i < count; ++i) {
            const double wl = min_wavelength + (max_wavelength - min_wavelength) * unit(rng);
            const double dir = kTwoPi * unit(rng), k = kTwoPi / wl;
            Wave w{k * std::cos(dir), k * std::sin(dir), kTwoPi * unit(rng), {}};
            for (double& a : w.amp) a = amplitude * (2.0 * unit(rng) - 1.0);
            waves.push_back(w);
        }
    }
    [[nodiscard]] Vec3d at(double x, double y) const {
        Vec3d d{};
        for (const Wave& w : waves) {
            const double s = std::sin(w.kx * x + w.ky * y + w.phase);
            d += Vec3d{w.amp[0] * s, w.amp[1] * s, w.amp[2] * s};
        }
        return d;
    }
    [[nodiscard]] Vec3d at(const Vec3d& p) const { return at(p.x, p.y); }
};

}  // namespace weft::test
