// The energy guard on the cuda backend (energy_kernels.cu): the device audit gives the host audit's
// sums on the same state (float against double), and the guard catches the loose drape there too.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "weft/backend/backend.h"
#include "weft/backend/energy_audit.h"
#include "weft/backend/model.h"
#include "weft/grab.h"

#include "gpu_test_util.h"
#include "stability_matrix.h"

namespace weft {
namespace {

using test::make_world;

void expect_close(double device, double host, double scale, const char* what, const std::string& scene) {
    EXPECT_NEAR(device, host, 1e-4 * scale + 1e-9) << scene << ": " << what;
}

// hanging: pins and bending; drape: the ball's contact, and with contacts at the triangles'
// centroids too (a coarse drape, so that the centroids sag onto the ball); flag: a capsule, pins and a
// grab.
TEST(CudaEnergyAudit, DeviceSumsMatchTheHostAudit) {
    WEFT_REQUIRE_GPU();
    const std::vector<std::string> faces{"solver.face_contacts=true", "cloth.cloth.mesh.grid.cells=[12,12]"};
    for (const std::string scene : {"hanging", "drape", "drape with face contacts", "flag"}) {
        const bool with_faces = scene == "drape with face contacts";
        const auto world = with_faces ? make_world("drape", "cuda", faces) : make_world(scene, "cuda");
        const int frames = scene.starts_with("drape") ? 20 : 10;  // the drape touches the ball from frame 13
        for (int f = 0; f < frames; ++f) (void)world->step();
        if (scene == "flag") test::grab_last_vertex_and_step(*world);  // the grab's power in the audit
        // With the wind's power (the flag's wind and gusts; nothing on the others).
        const auto [device, host, scale] = test::audit_device_and_host(*world);
        std::printf("[ audit    ] %s: device K %.6e G %.6e U %.6e C %.3e P %.3e | host K %.6e G %.6e U %.6e C %.3e P %.3e\n",
                    scene.c_str(), device.kinetic, device.gravity, device.elastic, device.contact, device.external_power,
                    host.kinetic, host.gravity, host.elastic, host.contact, host.external_power);
        expect_close(device.kinetic, host.kinetic, scale, "kinetic", scene);
        expect_close(device.gravity, host.gravity, scale, "gravity", scene);
        expect_close(device.elastic, host.elastic, scale, "elastic", scene);
        expect_close(device.contact, host.contact, scale, "contact", scene);
        // Power bounds: float rounding of forces and velocities only.
        EXPECT_NEAR(device.external_power, host.external_power, 1e-3 * host.external_power + 1e-6) << scene;
        EXPECT_EQ(device.bounded, host.bounded) << scene;
        if (scene.starts_with("drape")) {
            EXPECT_GT(host.contact, 0.0) << "the drape lies on the ball";
        }
        if (scene == "hanging") {
            EXPECT_GT(host.elastic, 0.0);
        }
        if (scene == "flag") {
            EXPECT_GT(host.external_power, 0.0) << "the wind and the grab work on the flag";
        }
    }
}

// The mid-edge model's bending energy is its minimum over the edge normals: the device audit relaxes
// them at the audited state as the host audit does. Audited at a state the solver did not step last
// (the cantilever's frame 15 written back at frame 30), so that normals left over from the last solve
// would show; the shell model (the same angles read without the normals' turns and the clamp's
// scales) puts a different energy on the same state.
TEST(CudaEnergyAudit, MidEdgeBendingEnergyMatchesTheHostAudit) {
    WEFT_REQUIRE_GPU();
    const auto world = make_world("cantilever", "cuda",
                                  {"solver.cg_tolerance=1e-4", "solver.cg_max_iterations=5000", "solver.bending=\"midedge\""});
    std::vector<Vec3d> earlier;
    for (int f = 0; f < 30; ++f) {
        (void)world->step();
        if (f == 14) earlier = world->positions(0);
    }
    const std::vector<Vec3d> still(earlier.size());
    world->set_state(0, earlier, still);
    const auto [device, host, scale] = test::audit_device_and_host(*world);
    world->settings().solver.bending = BendingModel::Shell;
    const auto shell = test::audit_device_and_host(*world);
    std::printf("[ audit    ] cantilever at frame 15, written back: mid-edge device U %.9e host U %.9e | shell device U %.9e "
                "host U %.9e\n",
                device.elastic, host.elastic, shell.device.elastic, shell.host.elastic);
    ASSERT_GT(host.elastic, 0.0);
    // Float positions and rest data against double: 2.9e-6 of the energy with either model (one H200).
    EXPECT_NEAR(device.elastic, host.elastic, 3e-5 * host.elastic) << "mid-edge";
    EXPECT_NEAR(shell.device.elastic, shell.host.elastic, 3e-5 * shell.host.elastic) << "shell";
    EXPECT_GT(std::abs(shell.host.elastic - host.elastic), 1e-3 * host.elastic) << "the two models' energies are the same";
}

// Offset contact (collision.mode = offset): the device audit adds the offset contacts' penalty energy
// to the colliders' (the host audit of the same backend has no contact list, so the difference is
// that energy); it is positive once the sheets of `layers` lie on each other.
TEST(CudaEnergyAudit, OffsetContactEnergyIsInTheDeviceAudit) {
    WEFT_REQUIRE_GPU();
    const auto world = make_world("layers", "cuda", {"collision.mode=offset"});
    int contacts = 0;
    for (int f = 0; f < 40; ++f) contacts = world->step().collision.contacts;
    ASSERT_GT(contacts, 0) << "the sheets never met";
    const Model& model = world->model();
    const double t = world->time(), h = model.settings.solver.dt / model.settings.solver.substeps;
    Backend& backend = world->backend();
    const EnergyAudit device = backend.energy_audit(model, t, h, false);
    const EnergyAudit host = backend.Backend::energy_audit(model, t, h, false);
    const double offset = device.contact - host.contact;
    std::printf("[ audit    ] layers offset: %d contacts, offset contact energy %.3e J, elastic %.3e J\n", contacts, offset,
                host.elastic);
    EXPECT_GT(offset, 0.0);
    EXPECT_TRUE(std::isfinite(offset));
    EXPECT_NEAR(device.elastic, host.elastic, 1e-4 * (std::abs(host.elastic) + std::abs(host.kinetic)) + 1e-9);
}

TEST(CudaEnergyAudit, GuardCatchesTheLooseDrapeOnTheGpu) {
    WEFT_REQUIRE_GPU();
    // The editor's 'loose' preset (tests/solver/test_energy_guard.cpp).
    const std::vector<std::string> loose{"solver.substeps=1", "solver.cg_tolerance=1e-2", "solver.cg_max_iterations=50",
                                         "solver.energy_guard=\"report\""};
    const auto world = make_world("drape", "cuda", loose);
    int gained = 0;
    for (int f = 0; f < 60; ++f) gained += world->step().energy_gained;
    std::printf("[ guard    ] loose drape on cuda: %d substeps gained energy in 60 frames\n", gained);
    EXPECT_GT(gained, 0);
    // Converged, the same scene gains nothing.
    const auto converged = make_world("drape", "cuda");
    int false_alarms = 0;
    for (int f = 0; f < 45; ++f) false_alarms += converged->step().energy_gained;
    EXPECT_EQ(false_alarms, 0);
}

// The line search on the device (DeviceSolver::line_search): the stiff (1e7 N/m), light (0.01 kg/m²)
// sheet at 1/24 s gains energy under plain Newton on the GPU as on the CPU; with the search, no
// substep gains and the run is stable (the matrix's criterion), and the search did halve updates.
TEST(CudaLineSearch, KeepsPlainNewtonFromGainingEnergyOnAStiffLightSheet) {
    WEFT_REQUIRE_GPU();
    const test::StabilityCase* corner = nullptr;
    static const std::vector<test::StabilityCase> cases = test::stability_cases(true);
    for (const test::StabilityCase& k : cases)
        if (k.name == "corner stiff no-bending light dt 1/24") corner = &k;
    ASSERT_NE(corner, nullptr) << "the stability matrix lost its stiff light corner";
    const test::StabilityResult plain = test::run_stability_case(*corner, "cuda", BendingModel::Hinge, 300, EnergyGuard::Report, false);
    const test::StabilityResult searched = test::run_stability_case(*corner, "cuda", BendingModel::Hinge, 300, EnergyGuard::Report, true);
    std::printf("[ search   ] stiff light sheet at 1/24 s on cuda: plain Newton %d substeps gained %.3g J; with the line "
                "search %d gained %.3g J (%s)\n",
                plain.energy_gained, plain.energy_gain, searched.energy_gained, searched.energy_gain,
                test::outcome_name(searched.outcome));
    EXPECT_GT(plain.energy_gained, 0) << "plain Newton no longer gains energy here: the test lost its point";
    EXPECT_EQ(searched.energy_gained, 0) << searched.energy_gain << " J gained with the line search";
    EXPECT_EQ(searched.outcome, test::StabilityOutcome::Stable) << searched.detail;
}

// The search's halvings reach the stats: a stiff light sheet over a long step backtracks with the
// search on, and the same world with it off reports none.
TEST(CudaLineSearch, HalvingsReachTheStats) {
    WEFT_REQUIRE_GPU();
    const std::vector<std::string> stiff{"solver.dt=0.041666667", "solver.substeps=1", "cloth.0.material.stretch_stiffness=1e7",
                                         "cloth.0.density=0.01"};
    std::vector<std::string> searching = stiff;
    searching.push_back("solver.line_search=true");
    const auto on = make_world("drape", "cuda", searching);
    const auto off = make_world("drape", "cuda", stiff);
    int halvings_on = 0, halvings_off = 0;
    for (int f = 0; f < 12; ++f) {
        halvings_on += on->step().line_search_halvings;
        halvings_off += off->step().line_search_halvings;
    }
    std::printf("[ search   ] stiff light drape at 1/24 s on cuda, 12 frames: %d halvings\n", halvings_on);
    EXPECT_GT(halvings_on, 0) << "a stiff light sheet over a long step never backtracked";
    EXPECT_EQ(halvings_off, 0);
}

}  // namespace
}  // namespace weft
