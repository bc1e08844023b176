#include "ray_export.h"

#include <kdrt/error.h>

#include <fstream>
#include <limits>

namespace kdrt::bench {

namespace {

template <class T>
void write_array(const std::filesystem::path& path, const std::vector<T>& v) {
    std::ofstream f(path, std::ios::binary);
    f.write(reinterpret_cast<const char*>(v.data()), static_cast<std::streamsize>(v.size() * sizeof(T)));
    if (!f) throw Error(ErrorCode::Io, path.string() + ": cannot write");
}

}  // namespace

RayExport::RayExport(const std::filesystem::path& dir, const Scene& scene) : dir_(dir), name_(scene.name) {
    const Mesh& mesh = scene.meshes.at(0);
    std::vector<float> vertices;
    for (const glm::dvec3& p : mesh.positions)
        for (int a = 0; a < 3; ++a) vertices.push_back(static_cast<float>(p[a]));
    std::vector<std::uint32_t> triangles;
    for (const MeshTriangle& t : mesh.triangles) triangles.insert(triangles.end(), t.v.begin(), t.v.end());
    std::filesystem::create_directories(dir);
    write_array(dir / (name_ + "-vertices.f32"), vertices);
    write_array(dir / (name_ + "-triangles.u32"), triangles);
    index_ = {{"input", name_}, {"vertices", name_ + "-vertices.f32"}, {"triangles", name_ + "-triangles.u32"},
              {"sets", Json::array()}};
}

void RayExport::rays(const std::string& set_name, std::span<const QueryRay> rays) {
    std::vector<float> values;
    for (const QueryRay& q : rays) {
        values.insert(values.end(), q.origin, q.origin + 3);
        values.insert(values.end(), q.direction, q.direction + 3);
    }
    const std::string file = name_ + "-" + set_name + ".f32";
    write_array(dir_ / file, values);
    index_["sets"].push_back({{"rays", set_name}, {"count", rays.size()}, {"file", file}});
}

void RayExport::answers(bool any, const std::vector<std::int32_t>& ids, const std::vector<float>& ts) {
    Json& set = index_["sets"].back();
    const std::string file = name_ + "-" + set["rays"].get<std::string>() + (any ? "-any.u8" : "-closest-t.f32");
    if (any) {
        write_array(dir_ / file, std::vector<std::uint8_t>(ids.begin(), ids.end()));
    } else {
        std::vector<float> t(ts);
        for (std::size_t i = 0; i < t.size(); ++i)
            if (ids[i] < 0) t[i] = std::numeric_limits<float>::infinity();
        write_array(dir_ / file, t);
    }
    set[any ? "any_hit" : "closest_t"] = file;
}

void RayExport::finish() const {
    const std::filesystem::path path = dir_ / (name_ + ".json");
    std::ofstream f(path);
    f << index_.dump(1) << "\n";
    if (!f) throw Error(ErrorCode::Io, path.string() + ": cannot write");
}

bool one_mesh(const Scene& scene) {
    return scene.meshes.size() == 1 && scene.spheres.empty() && scene.triangles.size() == 0;
}

}  // namespace kdrt::bench
