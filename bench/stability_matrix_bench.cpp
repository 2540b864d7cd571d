// The stability matrix (issue 22; tests/common/stability_matrix.h): every case on the asked backends
// and the three bending models, each either stable or refused with a message, or failing by name. Markdown
// table on stdout, JSON with --json; exit status 0 whatever the outcomes (it measures; the test
// asserts).
//
//   weft_stability_bench [--backends cpu,cuda] [--small] [--only TEXT] [--json FILE]
//
// --only runs the cases whose name contains TEXT (e.g. "dt 1/24").
#include <cstdio>
#include <string>
#include <vector>

#include "json_file.h"
#include "json_writer.h"
#include "stability_matrix.h"
#include "optional_backends.h"
#include "weft/error.h"

namespace {

std::vector<std::string> split(const std::string& value) {
    std::vector<std::string> out;
    std::size_t at = 0;
    while (at <= value.size()) {
        const std::size_t comma = value.find(',', at);
        out.push_back(value.substr(at, comma == std::string::npos ? std::string::npos : comma - at));
        if (comma == std::string::npos) break;
        at = comma + 1;
    }
    return out;
}

}  // namespace

int main(int argc, char** argv) {
    using namespace weft;
    try {
        weft::bench::install_optional_backends();
        std::vector<std::string> backends{"cpu"};
        bool small = false;
        std::string json, only;
        for (int i = 1; i < argc; ++i) {
            const std::string flag = argv[i];
            if (flag == "--small") {
                small = true;
                continue;
            }
            if (i + 1 >= argc) throw Error(flag + " needs a value");
            const std::string value = argv[++i];
            if (flag == "--backends")
                backends = split(value);
            else if (flag == "--json")
                json = value;
            else if (flag == "--only")
                only = value;
            else
                throw Error("unknown option '" + flag + "' (--backends, --small, --only, --json)");
        }
        struct Row {
            test::StabilityCase c;
            std::string backend, model;
            test::StabilityResult r;
        };
        std::vector<Row> rows;
        std::printf("| case | backend | bending | outcome | steps | substeps gaining energy | deepest in the ball, mm | s | detail |\n");
        std::printf("|---|---|---|---|---|---|---|---|---|\n");
        int failing = 0, total = 0;
        for (const test::StabilityCase& c : test::stability_cases(!small)) {
            if (!only.empty() && c.name.find(only) == std::string::npos) continue;
            for (const std::string& backend : backends)
                for (const BendingModel m : {BendingModel::Hinge, BendingModel::Shell, BendingModel::MidEdge}) {
                    const test::StabilityResult r = test::run_stability_case(c, backend, m);
                    const char* model = m == BendingModel::Hinge ? "hinge" : m == BendingModel::Shell ? "shell" : "midedge";
                    std::printf("| %s | %s | %s | %s | %d | %d | %.2f | %.2f | %s |\n", c.name.c_str(), backend.c_str(), model,
                                test::outcome_name(r.outcome), r.steps, r.energy_gained, 1000.0 * r.deepest, r.seconds,
                                r.detail.c_str());
                    std::fflush(stdout);
                    ++total;
                    if (r.outcome != test::StabilityOutcome::Stable && r.outcome != test::StabilityOutcome::Refused) ++failing;
                    rows.push_back({c, backend, model, r});
                }
        }
        std::printf("\n%d of %d cells stable or refused\n", total - failing, total);
        if (!json.empty() && !bench::write_json_file(json, "weft_stability_bench", [&](std::ostream& out) {
                json::JsonWriter w(out);
                w.begin_array();
                for (const Row& row : rows)
                    w.begin_object()
                        .field("case", row.c.name)
                        .field("backend", row.backend)
                        .field("bending", row.model)
                        .field("outcome", test::outcome_name(row.r.outcome))
                        .field("steps", row.r.steps)
                        .field("energy_gained_substeps", row.r.energy_gained)
                        .field("deepest_m", row.r.deepest)
                        .field("seconds", row.r.seconds)
                        .field("detail", row.r.detail)
                        .end_object();
                w.end_array();
            }))
            return 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "weft_stability_bench: %s\n", e.what());
        return 1;
    }
    return 0;
}
