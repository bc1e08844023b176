// Wavefront OBJ meshes for scene files (FORMAT.md "meshes").
//
// tinyobjloader does the parsing, but it is lenient: it drops faces with fewer
// than 3 vertices and only warns about out-of-range indices. We want those to
// be errors that name the line, so a light pre-scan records the line of every
// statement we use, and tinyobjloader is asked not to triangulate so that our
// own fan (v0, vi, vi+1) fixes the triangle order FORMAT.md's ids depend on.
#include "scene/affine_transform.h"

#include <kdrt/error.h>
#include <kdrt/scene.h>
#include <kdrt/scene_loader.h>

#include <tiny_obj_loader.h>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_inverse.hpp>
#include <glm/mat3x3.hpp>

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

namespace kdrt {
namespace {

[[noreturn]] void fail(const std::filesystem::path& path, std::size_t line, const std::string& what) {
    std::string where = path.string();
    if (line > 0) where += ":" + std::to_string(line);
    throw Error(ErrorCode::InvalidScene, where + ": " + what);
}

std::string read_text(const std::filesystem::path& path) {
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec))
        throw Error(ErrorCode::Io, path.string() + ": is a directory, not an OBJ file");
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error(ErrorCode::Io, path.string() + ": cannot open: " + std::strerror(errno));
    std::ostringstream text;
    text << in.rdbuf();
    if (in.bad()) throw Error(ErrorCode::Io, path.string() + ": read failed");
    return text.str();
}

// 1-based line numbers of the statements tinyobjloader turns into data, in
// file order, so that the k-th face it returns can be traced to its line.
struct ObjLines {
    std::vector<std::string> text;  // every line, index = line number - 1
    std::vector<std::size_t> positions, normals, faces;
};

bool is_blank(char c) { return c == ' ' || c == '\t'; }

// Splits lines and classifies them the way tinyobjloader does (line ends
// \n, \r\n or \r; statement keyword after leading blanks).
ObjLines scan(const std::filesystem::path& path, const std::string& text) {
    ObjLines lines;
    std::size_t i = 0;
    while (i < text.size()) {
        std::size_t end = text.find_first_of("\r\n", i);
        if (end == std::string::npos) end = text.size();
        lines.text.push_back(text.substr(i, end - i));
        i = end;
        if (i < text.size() && text[i] == '\r') ++i;
        if (i < text.size() && text[i] == '\n') ++i;  // \n alone or the \n of \r\n
    }
    for (std::size_t n = 0; n < lines.text.size(); ++n) {
        const std::string& s = lines.text[n];
        std::size_t k = s.find_first_not_of(" \t");
        if (k == std::string::npos) continue;
        std::string_view t(s.c_str() + k);
        auto statement = [&](std::string_view keyword) {
            return t.substr(0, keyword.size()) == keyword && t.size() > keyword.size() &&
                   is_blank(t[keyword.size()]);
        };
        if (statement("v")) {
            lines.positions.push_back(n + 1);
        } else if (statement("vn")) {
            lines.normals.push_back(n + 1);
        } else if (statement("f")) {
            std::size_t corners = 0;
            std::istringstream words{std::string(t.substr(1))};
            for (std::string w; words >> w;) ++corners;
            if (corners < 3)
                fail(path, n + 1, "face with " + std::to_string(corners) + " vertices (needs at least 3)");
            lines.faces.push_back(n + 1);
        }
    }
    return lines;
}

std::size_t line_of(const std::vector<std::size_t>& lines, std::size_t k) {
    return k < lines.size() ? lines[k] : 0;
}

// tinyobjloader reports a parse failure as "... line N.)"; turn that into a
// message that quotes the offending line.
[[noreturn]] void fail_parse(const std::filesystem::path& path, const ObjLines& lines,
                             const std::string& err) {
    std::size_t at = err.find("line ");
    while (at != std::string::npos && !(at + 5 < err.size() && std::isdigit(static_cast<unsigned char>(err[at + 5]))))
        at = err.find("line ", at + 1);
    if (at != std::string::npos) {
        std::size_t line = std::stoul(err.substr(at + 5));
        if (line >= 1 && line <= lines.text.size())
            fail(path, line, "cannot parse \"" + lines.text[line - 1] +
                                 "\" (indices start at 1 and must be numbers)");
    }
    std::string first = err.substr(0, err.find('\n'));
    fail(path, 0, "cannot parse: " + (first.empty() ? std::string("unknown error") : first));
}

void check_transform(const std::array<double, 16>& m) {
    if (const std::string problem = detail::affine_transform_problem(m); !problem.empty())
        throw Error(ErrorCode::InvalidArgument, "OBJ transform: " + problem);
}

}  // namespace

Mesh load_obj_mesh(const std::filesystem::path& path, const std::array<double, 16>& transform,
                   MaterialId material) {
    check_transform(transform);
    // glm is column-major: a[col][row] = transform[row * 4 + col].
    glm::dmat3 a;
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) a[c][r] = transform[static_cast<std::size_t>(r * 4 + c)];
    const glm::dvec3 translation{transform[3], transform[7], transform[11]};
    const glm::dmat3 normal_matrix = glm::inverseTranspose(a);

    const std::string text = read_text(path);
    const ObjLines lines = scan(path, text);

    tinyobj::attrib_t attrib;
    std::vector<tinyobj::shape_t> shapes;
    std::vector<tinyobj::material_t> obj_materials;
    std::string warn, err;
    std::istringstream in(text);
    // No MaterialReader: OBJ materials are ignored, and mtllib files are not opened.
    if (!tinyobj::LoadObj(&attrib, &shapes, &obj_materials, &warn, &err, &in, nullptr,
                          /*triangulate=*/false))
        fail_parse(path, lines, err);

    Mesh mesh;
    const std::size_t vertex_count = attrib.vertices.size() / 3;
    const std::size_t normal_count = attrib.normals.size() / 3;
    mesh.positions.reserve(vertex_count);
    for (std::size_t i = 0; i < vertex_count; ++i) {
        glm::dvec3 p{attrib.vertices[3 * i], attrib.vertices[3 * i + 1], attrib.vertices[3 * i + 2]};
        p = a * p + translation;
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
            fail(path, line_of(lines.positions, i), "vertex position is not finite");
        mesh.positions.push_back(p);
    }
    mesh.normals.reserve(normal_count);
    for (std::size_t i = 0; i < normal_count; ++i) {
        glm::dvec3 n{attrib.normals[3 * i], attrib.normals[3 * i + 1], attrib.normals[3 * i + 2]};
        n = normal_matrix * n;
        double len = glm::length(n);
        if (!(len > 0.0) || !std::isfinite(len))
            fail(path, line_of(lines.normals, i), "vertex normal has zero length or is not finite");
        mesh.normals.push_back(n / len);
    }

    // Faces come out shape by shape, each in file order, so their running
    // count indexes lines.faces.
    std::size_t face = 0;
    for (const tinyobj::shape_t& shape : shapes) {
        std::size_t offset = 0;
        for (unsigned corners : shape.mesh.num_face_vertices) {
            const std::size_t line = line_of(lines.faces, face++);
            const tinyobj::index_t* c = &shape.mesh.indices[offset];
            offset += corners;
            bool all_normals = true;
            for (unsigned k = 0; k < corners; ++k) {
                int v = c[k].vertex_index, n = c[k].normal_index;
                if (v < 0 || static_cast<std::size_t>(v) >= vertex_count)
                    fail(path, line, "vertex index out of range (the file defines " +
                                         std::to_string(vertex_count) + " vertices)");
                // -1 means "no normal"; a relative index before the first normal is < -1.
                if (n < -1 || (n >= 0 && static_cast<std::size_t>(n) >= normal_count))
                    fail(path, line, "normal index out of range (the file defines " +
                                         std::to_string(normal_count) + " normals)");
                all_normals = all_normals && n >= 0;
            }
            // Fan around the first corner. A corner without a normal makes the
            // whole face use its geometric normal rather than a half-defined one.
            for (unsigned k = 1; k + 1 < corners; ++k) {
                MeshTriangle t;
                t.v = {static_cast<std::uint32_t>(c[0].vertex_index),
                       static_cast<std::uint32_t>(c[k].vertex_index),
                       static_cast<std::uint32_t>(c[k + 1].vertex_index)};
                if (all_normals)
                    t.n = {static_cast<std::uint32_t>(c[0].normal_index),
                           static_cast<std::uint32_t>(c[k].normal_index),
                           static_cast<std::uint32_t>(c[k + 1].normal_index)};
                t.material = material;
                mesh.triangles.push_back(t);
            }
        }
    }
    if (face != lines.faces.size())
        fail(path, 0, "internal error: " + std::to_string(face) + " faces parsed but " +
                          std::to_string(lines.faces.size()) + " face lines found");
    // tinyobjloader accepts any text; an OBJ without faces is most likely the wrong file.
    if (mesh.triangles.empty()) fail(path, 0, "no faces found (is this an OBJ file?)");
    return mesh;
}

}  // namespace kdrt
