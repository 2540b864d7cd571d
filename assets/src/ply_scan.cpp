// PLY header check (ply_scan.h).
#include "ply_scan.h"

#include <array>
#include <fstream>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "weft/error.h"

namespace weft::assets {
namespace {

constexpr std::size_t kHeaderLimit = 64 * 1024;
constexpr std::uint64_t kElementLimit = 1ULL << 32;

/// Bytes of a PLY scalar type, 0 when the name is not one.
std::uint64_t type_bytes(std::string_view t) {
    if (t == "char" || t == "uchar" || t == "int8" || t == "uint8") return 1;
    if (t == "short" || t == "ushort" || t == "int16" || t == "uint16") return 2;
    if (t == "int" || t == "uint" || t == "float" || t == "int32" || t == "uint32" || t == "float32") return 4;
    if (t == "double" || t == "float64") return 8;
    return 0;
}

struct Property {
    bool list = false;
    std::string name;
};

struct Element {
    std::string name;
    std::uint64_t count = 0;
    std::uint64_t fixed_bytes = 0;  ///< per element: its scalars and its lists' count fields
    std::vector<Property> properties;
};

/// The largest list an ASCII element line may hold (a polygon's corners).
constexpr long long kListLimit = 4096;

/// Checks one ASCII element line against its element's properties: every token a number, each list
/// as long as its count says, a face's vertex indices in range. Throws naming the line.
void check_ascii_line(const std::string& line, const Element& e, std::uint64_t vertices, const std::string& where) {
    // Numbers apart by spaces and tabs only: assimp's reader splits on those alone, so a form feed
    // between two numbers shifted its reading of the lines after it and made its triangulation
    // abort (found by fuzz_mesh_import).
    for (const char c : line)
        if ((c < ' ' || c > '~') && c != '\t' && c != '\r')
            throw Error(where + "a control or non-ASCII character in a " + e.name + " line");
    std::istringstream in(line);
    std::vector<std::string> tokens;
    for (std::string t; in >> t;) tokens.push_back(t);
    std::size_t at = 0;
    const auto number = [&](const std::string& what) {
        if (at >= tokens.size()) throw Error(where + e.name + " line ends before its " + what);
        const std::string& t = tokens[at++];
        try {
            std::size_t used = 0;
            const double v = std::stod(t, &used);
            if (used != t.size()) throw std::invalid_argument(t);
            return v;
        } catch (const std::exception&) {
            throw Error(where + e.name + " line: '" + t.substr(0, 20) + "' is not a number");
        }
    };
    for (const Property& p : e.properties) {
        if (!p.list) {
            (void)number(p.name);
            continue;
        }
        const double count = number(p.name + " count");
        if (!(count >= 0.0 && count <= static_cast<double>(kListLimit)) || count != static_cast<double>(static_cast<long long>(count)))
            throw Error(where + e.name + " line: a list of " + tokens[at - 1].substr(0, 20) + " items");
        const bool indices = e.name == "face" && (p.name == "vertex_indices" || p.name == "vertex_index");
        for (long long k = 0; k < static_cast<long long>(count); ++k) {
            const double v = number(p.name + " item");
            if (indices && !(v >= 0.0 && v < static_cast<double>(vertices)))
                throw Error(where + "face line: vertex index " + tokens[at - 1].substr(0, 20) + " of " + std::to_string(vertices) +
                            " vertices");
        }
    }
    if (at != tokens.size()) throw Error(where + e.name + " line has " + std::to_string(tokens.size() - at) + " numbers too many");
}

}  // namespace

PlyScan scan_ply(const std::filesystem::path& path) {
    const std::string file = path.string();
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error(file + ": cannot read the mesh file");
    PlyScan s;
    std::vector<Element> elements;
    std::string line;
    std::size_t number = 0;
    bool ended = false;
    while (!ended && std::getline(in, line)) {
        ++number;
        s.header_bytes += line.size() + 1;
        if (s.header_bytes > kHeaderLimit) break;
        if (!line.empty() && line.back() == '\r') line.pop_back();
        // Printable ASCII, spaces and tabs only: assimp reads a header line with other whitespace in
        // it (a vertical tab after `end_header`) as no end at all and loops (fuzz_mesh_import).
        for (const char c : line)
            if ((c < ' ' || c > '~') && c != '\t')
                throw Error(file + ":" + std::to_string(number) + ": a control or non-ASCII character in the PLY header");
        std::istringstream words(line);
        std::string word;
        words >> word;
        const std::string where = file + ":" + std::to_string(number) + ": ";
        if (number == 1) {
            if (line != "ply") throw Error(file + ": not a PLY file (no 'ply' on the first line)");
            continue;
        }
        if (word == "format") {
            std::string kind, version;
            words >> kind >> version;
            if (kind != "ascii" && kind != "binary_little_endian" && kind != "binary_big_endian")
                throw Error(where + "unknown PLY format '" + kind + "'");
            s.binary = kind != "ascii";
        } else if (word == "element") {
            Element e;
            std::string count;
            words >> e.name >> count;
            try {
                std::size_t used = 0;
                e.count = std::stoull(count, &used);
                if (used != count.size()) throw std::invalid_argument(count);
            } catch (const std::exception&) {
                throw Error(where + "element '" + e.name + "' has count '" + count + "', not a number");
            }
            if (e.count > kElementLimit) throw Error(where + "element '" + e.name + "' declares " + count + " entries");
            elements.push_back(e);
        } else if (word == "property") {
            if (elements.empty()) throw Error(where + "a property before any element");
            std::string type;
            words >> type;
            if (type == "list") {
                std::string count_type, item_type;
                words >> count_type >> item_type;
                if (type_bytes(count_type) == 0 || type_bytes(item_type) == 0)
                    throw Error(where + "a list of unknown types '" + count_type + "' '" + item_type + "'");
                elements.back().fixed_bytes += type_bytes(count_type);
                std::string name;
                words >> name;
                elements.back().properties.push_back({true, name});
            } else {
                if (type_bytes(type) == 0) throw Error(where + "unknown property type '" + type + "'");
                elements.back().fixed_bytes += type_bytes(type);
                std::string name;
                words >> name;
                elements.back().properties.push_back({false, name});
            }
        } else if (word == "end_header") {
            if (line.find_first_not_of(" \t", line.find("end_header") + 10) != std::string::npos)
                throw Error(where + "text after end_header on its line");
            ended = true;
        } else if (word != "comment" && word != "obj_info" && !word.empty()) {
            throw Error(where + "unknown header line '" + line.substr(0, 40) + "'");
        }
    }
    if (!ended) throw Error(file + ": the PLY header has no end_header line in its first 64 KiB");
    std::uint64_t needed = 0;  // binary: bytes; ASCII: lines
    for (const Element& e : elements) {
        if (e.name == "vertex") s.vertices = e.count;
        if (e.name == "face") s.faces = e.count;
        needed += s.binary ? e.count * e.fixed_bytes : e.count;
    }
    std::error_code ec;
    const std::uint64_t size = std::filesystem::file_size(path, ec);
    if (ec) throw Error(file + ": cannot read the mesh file's size");
    if (s.binary) {
        if (size - s.header_bytes < needed)
            throw Error(file + ": the header declares " + std::to_string(s.vertices) + " vertices and " +
                        std::to_string(s.faces) + " faces, at least " + std::to_string(needed) + " bytes of data; the file has " +
                        std::to_string(size - s.header_bytes) + " (cut short?)");
    } else {
        // Every element line checked in order (assimp 5.2 aborts in its post-processing on some
        // malformed ones: found by fuzz_mesh_import).
        std::uint64_t lines = 0;
        std::size_t element = 0;
        std::uint64_t in_element = 0;
        while (lines < needed && std::getline(in, line)) {
            ++number;
            if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
            while (element < elements.size() && in_element == elements[element].count) {
                ++element;
                in_element = 0;
            }
            if (element >= elements.size()) break;
            check_ascii_line(line, elements[element], s.vertices, file + ":" + std::to_string(number) + ": ");
            ++in_element;
            ++lines;
        }
        if (lines < needed)
            throw Error(file + ": the header declares " + std::to_string(needed) + " element lines (" + std::to_string(s.vertices) +
                        " vertices, " + std::to_string(s.faces) + " faces); the file has " + std::to_string(lines) + " (cut short?)");
    }
    return s;
}

}  // namespace weft::assets
