// OBJ pre-scan (obj_scan.h).
#include "obj_scan.h"

#include <charconv>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include "weft/error.h"

namespace weft::assets {

ObjScan scan_obj(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error(path.string() + ": cannot read the mesh file");
    ObjScan s;
    std::vector<std::pair<std::size_t, std::size_t>> referenced;  // (1-based vertex, line)
    std::string line;
    std::size_t number = 0;
    bool last_had_newline = true, last_incomplete = false;
    while (std::getline(in, line)) {
        ++number;
        last_had_newline = !in.eof();
        if (!line.empty() && line.back() == '\r') line.pop_back();
        // Geometry statements (v, vt, vn, vp, f, fo, l, p) must be what they say, in printable
        // ASCII: assimp reads any line that starts with 'f' as a face and overran its buffer on one
        // of 0xFF bytes (found by fuzz_mesh_import).
        if (!line.empty() && (line[0] == 'v' || line[0] == 'f' || line[0] == 'l' || line[0] == 'p')) {
            const std::string keyword = line.substr(0, line.find_first_of(" \t"));
            if (keyword != "v" && keyword != "vt" && keyword != "vn" && keyword != "vp" && keyword != "f" && keyword != "fo" &&
                keyword != "l" && keyword != "p")
                throw Error(path.string() + ":" + std::to_string(number) + ": not an OBJ statement");
            for (const char c : line)
                if ((c < ' ' || c > '~') && c != '\t')
                    throw Error(path.string() + ":" + std::to_string(number) + ": a control or non-ASCII character in a '" + keyword +
                                "' line");
        }
        if (line.size() > 1 && line[0] == 'v' && (line[1] == ' ' || line[1] == '\t')) {
            ++s.vertices;
            // Fewer than three coordinates: a line cut short.
            std::size_t numbers = 0;
            for (std::size_t k = 1; k < line.size(); ++k)
                numbers += (line[k] != ' ' && line[k] != '\t' && (line[k - 1] == ' ' || line[k - 1] == '\t')) ? 1 : 0;
            last_incomplete = numbers < 3;
            continue;
        }
        last_incomplete = false;
        if (line.size() < 2 || line[0] != 'f' || (line[1] != ' ' && line[1] != '\t')) continue;
        ++s.faces;
        std::size_t at = 1, corners = 0;
        while (at < line.size()) {
            while (at < line.size() && (line[at] == ' ' || line[at] == '\t')) ++at;
            if (at >= line.size()) break;
            long long index = 0;
            const char* first = line.data() + at;
            const auto [end, ec] = std::from_chars(first, line.data() + line.size(), index);
            if (ec != std::errc{} || index == 0)
                throw Error(path.string() + ":" + std::to_string(number) + ": a face index that is not a vertex number");
            // A relative index counts back from the last vertex read so far; a positive one may
            // name a vertex further down the file, so it is checked at the end.
            const long long resolved = index > 0 ? index : static_cast<long long>(s.vertices) + index + 1;
            if (resolved < 1)
                throw Error(path.string() + ":" + std::to_string(number) + ": face index " + std::to_string(index) + " of " +
                            std::to_string(s.vertices) + " vertices read so far");
            referenced.push_back({static_cast<std::size_t>(resolved), number});
            ++corners;
            at = static_cast<std::size_t>(end - line.data());
            while (at < line.size() && line[at] != ' ' && line[at] != '\t') ++at;  // the /vt/vn part
        }
        last_incomplete = corners < 3;
    }
    s.ends_mid_line = number > 0 && !last_had_newline && last_incomplete;
    std::vector<char> used(s.vertices, 0);
    for (const auto& [vertex, at_line] : referenced) {
        if (vertex > s.vertices)
            throw Error(path.string() + ":" + std::to_string(at_line) + ": face index " + std::to_string(vertex) + " of " +
                        std::to_string(s.vertices) + " vertices in the file");
        used[vertex - 1] = 1;
    }
    for (const char u : used) s.unreferenced += u == 0 ? 1 : 0;
    return s;
}

}  // namespace weft::assets
