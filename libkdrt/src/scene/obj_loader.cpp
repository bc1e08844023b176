// Wavefront OBJ meshes for scene files (FORMAT.md "meshes").
//
// A strict parser of the subset FORMAT.md uses: `v` positions, `vn` normals and
// `f` faces whose corners are v, v/vt, v//vn or v/vt/vn, 1-based or negative
// (relative) indices; `vt`, `vp`, `g`, `o`, `s`, `mtllib`, `usemtl` and comments
// are read and ignored. Whatever it cannot represent exactly (a non-finite or
// missing coordinate, a stray token, an index that is 0, out of range or does not
// fit 64 bits, a normal of zero length, an unknown statement) is an error naming
// the file, the line and the problem: a mesh is never silently changed.
//
// Speed: the text is cut into chunks at line ends and parsed in parallel (TBB).
// A first, cheap pass counts each chunk's lines, positions and normals, so the
// second pass knows every chunk's global offsets and resolves indices, including
// relative ones, directly. The result and the error reported (the one on the
// earliest line) do not depend on the number of threads.
#include "common/printable_text.h"
#include "common/read_input_file.h"
#include "scene/affine_transform.h"
#include "scene/parse_obj_mesh.h"

#include <kdrt/error.h>
#include <kdrt/scene.h>
#include <kdrt/scene_loader.h>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_inverse.hpp>
#include <glm/mat3x3.hpp>

#include <tbb/parallel_for.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

namespace kdrt {
namespace {

// Chunks are at least this large, so that small files are parsed in one go.
constexpr std::size_t kMinChunkBytes = std::size_t{1} << 18;
constexpr std::size_t kMaxChunks = 256;

// Iterates the lines of [begin, end): line ends are "\n", "\r\n" or "\r".
class LineReader {
public:
    LineReader(const char* begin, const char* end) : p_(begin), end_(end) {}

    bool next(std::string_view& line) {
        if (p_ == end_) return false;
        const auto* nl = static_cast<const char*>(std::memchr(p_, '\n', static_cast<std::size_t>(end_ - p_)));
        if (!nl) nl = end_;
        const auto* cr = static_cast<const char*>(std::memchr(p_, '\r', static_cast<std::size_t>(nl - p_)));
        if (cr) {
            line = std::string_view(p_, static_cast<std::size_t>(cr - p_));
            p_ = cr + 1;
            if (p_ < end_ && *p_ == '\n') ++p_;
        } else {
            line = std::string_view(p_, static_cast<std::size_t>(nl - p_));
            p_ = nl < end_ ? nl + 1 : end_;
        }
        return true;
    }

private:
    const char* p_;
    const char* end_;
};

bool is_blank(char c) { return c == ' ' || c == '\t'; }

// Splits a line into blank-separated tokens; a token starting with '#' ends it.
class Tokens {
public:
    explicit Tokens(std::string_view line) : rest_(line) {}

    std::optional<std::string_view> next() {
        std::size_t i = 0;
        while (i < rest_.size() && is_blank(rest_[i])) ++i;
        if (i == rest_.size() || rest_[i] == '#') {
            rest_ = {};
            return std::nullopt;
        }
        std::size_t j = i;
        while (j < rest_.size() && !is_blank(rest_[j])) ++j;
        std::string_view token = rest_.substr(i, j - i);
        rest_.remove_prefix(j);
        return token;
    }

private:
    std::string_view rest_;
};

enum class Statement { Position, Normal, Face, Ignored, Unknown };

Statement classify(std::string_view keyword) {
    if (keyword == "v") return Statement::Position;
    if (keyword == "vn") return Statement::Normal;
    if (keyword == "f") return Statement::Face;
    if (keyword == "vt" || keyword == "vp" || keyword == "g" || keyword == "o" || keyword == "s" ||
        keyword == "mtllib" || keyword == "usemtl")
        return Statement::Ignored;
    return Statement::Unknown;
}

// The first token of a line, cheaply: what pass 1 needs to count statements.
std::string_view keyword_of(std::string_view line) {
    std::size_t i = 0;
    while (i < line.size() && is_blank(line[i])) ++i;
    std::size_t j = i;
    while (j < line.size() && !is_blank(line[j])) ++j;
    return line.substr(i, j - i);
}

// A piece of the file, parsed on its own.
struct Chunk {
    const char* begin = nullptr;
    const char* end = nullptr;
    // Pass 1: what the chunk holds.
    std::size_t lines = 0, positions = 0, normals = 0;
    // Prefix sums over the chunks before this one.
    std::size_t first_line = 0, first_position = 0, first_normal = 0;
    // Pass 2: the chunk's triangles, and its first error.
    std::vector<MeshTriangle> triangles;
    std::size_t error_line = 0;  // 0 = none
    std::string error;
};

std::vector<Chunk> cut_into_chunks(std::string_view text) {
    const std::size_t chunk_bytes = std::max(kMinChunkBytes, text.size() / kMaxChunks + 1);
    std::vector<Chunk> chunks;
    const char* p = text.data();
    const char* end = text.data() + text.size();
    while (p < end) {
        const char* cut = end - p > static_cast<std::ptrdiff_t>(chunk_bytes) ? p + chunk_bytes : end;
        if (cut < end) {
            // Cut after a '\n', never inside a line (nor inside "\r\n").
            const auto* nl = static_cast<const char*>(std::memchr(cut, '\n', static_cast<std::size_t>(end - cut)));
            cut = nl ? nl + 1 : end;
        }
        Chunk c;
        c.begin = p;
        c.end = cut;
        chunks.push_back(std::move(c));
        p = cut;
    }
    return chunks;
}

void count_statements(Chunk& c) {
    LineReader lines(c.begin, c.end);
    for (std::string_view line; lines.next(line);) {
        ++c.lines;
        const std::string_view k = keyword_of(line);
        if (k == "v")
            ++c.positions;
        else if (k == "vn")
            ++c.normals;
    }
}

// Everything pass 2 needs about the whole file and the transform.
struct MeshContext {
    std::size_t position_count = 0, normal_count = 0;
    glm::dmat3 linear{1.0};
    glm::dvec3 translation{0.0};
    glm::dmat3 normal_matrix{1.0};
    MaterialId material = 0;
    Mesh* mesh = nullptr;  // positions and normals already sized
};

// A problem on one line; caught per chunk (exceptions must not cross TBB tasks
// unordered: the earliest line wins).
struct LineError {
    std::string what;
};

class ChunkParser {
public:
    ChunkParser(Chunk& chunk, const MeshContext& ctx) : c_(chunk), ctx_(ctx) {}

    void run() {
        LineReader lines(c_.begin, c_.end);
        std::size_t line_number = c_.first_line;
        for (std::string_view line; lines.next(line);) {
            ++line_number;
            try {
                parse_line(line);
            } catch (const LineError& e) {
                c_.error_line = line_number;
                c_.error = e.what + " in \"" + detail::printable(line) + "\"";
                return;
            }
        }
    }

private:
    [[noreturn]] static void fail(const std::string& what) { throw LineError{what}; }

    double number(std::optional<std::string_view> token, const char* what, std::size_t k) {
        if (!token) fail(std::string("missing ") + what + " " + std::to_string(k + 1));
        std::string_view t = *token;
        // from_chars takes no leading '+', OBJ writers sometimes do.
        if (t.size() > 1 && t[0] == '+' && t[1] != '-' && t[1] != '+') t.remove_prefix(1);
        double v = 0.0;
        const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
        if (ec == std::errc::result_out_of_range)
            fail(std::string(what) + " \"" + detail::printable(*token) + "\" is out of the range of a double");
        if (ec != std::errc() || end != t.data() + t.size())
            fail(std::string(what) + " \"" + detail::printable(*token) + "\" is not a number");
        if (!std::isfinite(v)) fail(std::string(what) + " \"" + detail::printable(*token) + "\" is not finite");
        return v;
    }

    glm::dvec3 vec3(Tokens& tokens, const char* what) {
        glm::dvec3 v;
        for (int k = 0; k < 3; ++k) v[k] = number(tokens.next(), what, static_cast<std::size_t>(k));
        return v;
    }

    void no_more(Tokens& tokens, const char* statement) {
        if (const auto extra = tokens.next())
            fail(std::string("unexpected \"") + detail::printable(*extra) + "\" after the " + statement);
    }

    // An OBJ index (1-based, or negative = relative to the `defined` items so
    // far) as a 0-based index below `total`.
    static std::uint32_t resolve(std::string_view token, std::size_t defined, std::size_t total, const char* what) {
        std::int64_t i = 0;
        const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), i);
        if (ec == std::errc::result_out_of_range)
            fail(std::string(what) + " index out of range: " + detail::printable(token) + " (the file defines " +
                 std::to_string(total) + " " + what + "s)");
        if (ec != std::errc() || end != token.data() + token.size())
            fail(std::string("cannot parse ") + what + " index \"" + detail::printable(token) + "\"");
        if (i == 0) fail(std::string("cannot parse ") + what + " index 0 (OBJ indices start at 1)");
        // Relative indices count back from the items defined so far.
        const std::int64_t zero_based = i > 0 ? i - 1 : static_cast<std::int64_t>(defined) + i;
        if (zero_based < 0 || static_cast<std::uint64_t>(zero_based) >= total)
            fail(std::string(what) + " index out of range: " + std::to_string(i) + " (the file defines " +
                 std::to_string(total) + " " + what + "s" +
                 (i < 0 ? ", " + std::to_string(defined) + " before this line)" : ")"));
        return static_cast<std::uint32_t>(zero_based);
    }

    void parse_line(std::string_view line) {
        Tokens tokens(line);
        const auto keyword = tokens.next();
        if (!keyword) return;
        switch (classify(*keyword)) {
            case Statement::Ignored: return;
            case Statement::Unknown:
                fail("unsupported statement \"" + detail::printable(*keyword) + "\"");
            case Statement::Position: {
                const glm::dvec3 p = ctx_.linear * vec3(tokens, "vertex coordinate") + ctx_.translation;
                // An RGB vertex colour (a common extension) is checked, not used.
                std::optional<std::string_view> extra[4];
                for (auto& e : extra) e = tokens.next();
                if (extra[0] && (!extra[2] || extra[3]))
                    fail("a vertex takes 3 coordinates, or 3 and an RGB colour");
                for (std::size_t k = 0; k < 3 && extra[0]; ++k) number(extra[k], "vertex colour component", k);
                if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
                    fail("vertex position is not finite after the mesh transform");
                ctx_.mesh->positions[c_.first_position + positions_++] = p;
                return;
            }
            case Statement::Normal: {
                const glm::dvec3 n = ctx_.normal_matrix * vec3(tokens, "normal coordinate");
                no_more(tokens, "3 coordinates of a normal");
                const double len = glm::length(n);
                if (!(len > 0.0) || !std::isfinite(len)) fail("vertex normal has zero length or is not finite");
                ctx_.mesh->normals[c_.first_normal + normals_++] = n / len;
                return;
            }
            case Statement::Face: parse_face(tokens); return;
        }
    }

    void parse_face(Tokens& tokens) {
        corners_v_.clear();
        corners_n_.clear();
        bool all_normals = true;
        const std::size_t positions_before = c_.first_position + positions_;
        const std::size_t normals_before = c_.first_normal + normals_;
        while (const auto corner = tokens.next()) {
            // v, v/vt, v//vn or v/vt/vn
            const std::string_view c = *corner;
            const std::size_t s1 = c.find('/');
            const std::string_view v = c.substr(0, s1);
            std::string_view vt, vn;
            if (s1 != std::string_view::npos) {
                const std::size_t s2 = c.find('/', s1 + 1);
                vt = c.substr(s1 + 1, s2 == std::string_view::npos ? std::string_view::npos : s2 - s1 - 1);
                if (s2 != std::string_view::npos) {
                    vn = c.substr(s2 + 1);
                    if (vn.empty() || vn.find('/') != std::string_view::npos)
                        fail("cannot parse face corner \"" + detail::printable(c) + "\"");
                }
                if (vt.empty() && s2 == std::string_view::npos)
                    fail("cannot parse face corner \"" + detail::printable(c) + "\"");
            }
            corners_v_.push_back(resolve(v, positions_before, ctx_.position_count, "vertex"));
            // Texture coordinates are not used; their index must still be an index.
            if (!vt.empty()) {
                std::int64_t t = 0;
                const auto [end, ec] = std::from_chars(vt.data(), vt.data() + vt.size(), t);
                if (ec != std::errc() || end != vt.data() + vt.size() || t == 0)
                    fail("cannot parse texture index \"" + detail::printable(vt) + "\"");
            }
            if (vn.empty()) {
                all_normals = false;
                corners_n_.push_back(kNoNormal);
            } else {
                corners_n_.push_back(resolve(vn, normals_before, ctx_.normal_count, "normal"));
            }
        }
        const std::size_t corners = corners_v_.size();
        if (corners < 3) fail("face with " + std::to_string(corners) + " vertices (needs at least 3)");
        // Fan around the first corner (FORMAT.md ids depend on this order). A
        // corner without a normal makes the whole face use its geometric normal
        // rather than a half-defined one.
        for (std::size_t k = 1; k + 1 < corners; ++k) {
            MeshTriangle t;
            t.v = {corners_v_[0], corners_v_[k], corners_v_[k + 1]};
            if (all_normals) t.n = {corners_n_[0], corners_n_[k], corners_n_[k + 1]};
            t.material = ctx_.material;
            c_.triangles.push_back(t);
        }
    }

    Chunk& c_;
    const MeshContext& ctx_;
    std::size_t positions_ = 0, normals_ = 0;
    std::vector<std::uint32_t> corners_v_, corners_n_;
};

[[noreturn]] void fail(const std::filesystem::path& path, std::size_t line, const std::string& what) {
    std::string where = path.string();
    if (line > 0) where += ":" + std::to_string(line);
    throw Error(ErrorCode::InvalidScene, where + ": " + what);
}

}  // namespace

Mesh detail::parse_obj_mesh(std::string_view text, const std::filesystem::path& path,
                            const std::array<double, 16>& transform, MaterialId material) {
    if (const std::string problem = detail::affine_transform_problem(transform); !problem.empty())
        throw Error(ErrorCode::InvalidArgument, "OBJ transform: " + problem);
    MeshContext ctx;
    // glm is column-major: a[col][row] = transform[row * 4 + col].
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) ctx.linear[c][r] = transform[static_cast<std::size_t>(r * 4 + c)];
    ctx.translation = {transform[3], transform[7], transform[11]};
    ctx.normal_matrix = glm::inverseTranspose(ctx.linear);
    ctx.material = material;

    std::vector<Chunk> chunks = cut_into_chunks(text);

    // Pass 1: counts, then every chunk's offsets.
    tbb::parallel_for(std::size_t{0}, chunks.size(), [&](std::size_t i) { count_statements(chunks[i]); });
    for (std::size_t i = 1; i < chunks.size(); ++i) {
        chunks[i].first_line = chunks[i - 1].first_line + chunks[i - 1].lines;
        chunks[i].first_position = chunks[i - 1].first_position + chunks[i - 1].positions;
        chunks[i].first_normal = chunks[i - 1].first_normal + chunks[i - 1].normals;
    }
    if (!chunks.empty()) {
        const Chunk& last = chunks.back();
        ctx.position_count = last.first_position + last.positions;
        ctx.normal_count = last.first_normal + last.normals;
    }
    // Indices are 32-bit and kNoNormal is reserved.
    if (ctx.position_count >= kNoNormal || ctx.normal_count >= kNoNormal)
        fail(path, 0, "too many vertices or normals for 32-bit indices");

    // Pass 2: parse, writing positions and normals in place.
    Mesh mesh;
    mesh.positions.resize(ctx.position_count);
    mesh.normals.resize(ctx.normal_count);
    ctx.mesh = &mesh;
    tbb::parallel_for(std::size_t{0}, chunks.size(), [&](std::size_t i) { ChunkParser(chunks[i], ctx).run(); });
    for (const Chunk& c : chunks)
        if (c.error_line != 0) fail(path, c.error_line, c.error);

    std::size_t triangle_count = 0;
    for (const Chunk& c : chunks) triangle_count += c.triangles.size();
    // Ids are 32-bit in the renderers too.
    if (triangle_count >= kNoNormal) fail(path, 0, "too many triangles for 32-bit ids");
    mesh.triangles.resize(triangle_count);
    std::vector<std::size_t> first_triangle(chunks.size(), 0);
    for (std::size_t i = 1; i < chunks.size(); ++i)
        first_triangle[i] = first_triangle[i - 1] + chunks[i - 1].triangles.size();
    tbb::parallel_for(std::size_t{0}, chunks.size(), [&](std::size_t i) {
        std::copy(chunks[i].triangles.begin(), chunks[i].triangles.end(),
                  mesh.triangles.begin() + static_cast<std::ptrdiff_t>(first_triangle[i]));
    });
    // An OBJ without faces is most likely the wrong file.
    if (mesh.triangles.empty()) fail(path, 0, "no faces found (is this an OBJ file?)");
    return mesh;
}

Mesh load_obj_mesh(const std::filesystem::path& path, const std::array<double, 16>& transform,
                   MaterialId material) {
    // The transform is checked before the file is read: a bad one is the caller's error.
    if (const std::string problem = detail::affine_transform_problem(transform); !problem.empty())
        throw Error(ErrorCode::InvalidArgument, "OBJ transform: " + problem);
    return detail::parse_obj_mesh(detail::read_input_bytes(path, "OBJ file").view(), path, transform, material);
}

}  // namespace kdrt
