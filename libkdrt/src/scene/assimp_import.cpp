// import_model's work where Assimp runs (the kdrt-import helper, or the
// calling process with ImportIsolation::InProcess): the file's bounds, then
// Assimp, then its node tree flattened into one kdrt Mesh (docs/IMPORT.md).
//
// Assimp is asked for as little as possible (triangulation and its own
// structure check); the node tree is walked here rather than with
// aiProcess_PreTransformVertices, which merges meshes by material and would
// reorder the triangles, and so the object ids. Everything Assimp hands back
// is checked again before use: its importers are lenient, and a NaN vertex or
// an index out of range must be an error naming the file, not a crash or a
// wrong picture.
#include "scene/assimp_import.h"

#include "common/read_input_file.h"
#include "scene/assimp_log_capture.h"
#include "scene/fbx_bounds_check.h"
#include "scene/gltf_bounds_check.h"
#include "scene/material_mapping.h"
#include "scene/model_file.h"
#include "scene/model_header_check.h"
#include "scene/regular_file_io.h"

#include <kdrt/error.h>
#include <kdrt/model_import.h>

#include <assimp/Importer.hpp>
#include <assimp/config.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_inverse.hpp>
#include <glm/mat3x3.hpp>
#include <glm/mat4x4.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <new>
#include <string>
#include <utility>
#include <vector>

namespace kdrt::detail {
namespace {

using Failure = ModelFailure;

constexpr double kPi = 3.14159265358979323846;
// FORMAT.md's object id limit (validate()): larger models are refused before allocating.
constexpr std::size_t kMaxTriangles = (std::size_t{1} << 30) - 1;

bool finite(const glm::dvec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

glm::dvec3 to_glm(const aiVector3D& v) { return {v.x, v.y, v.z}; }

glm::dmat4 to_glm(const aiMatrix4x4& m) {
    // aiMatrix4x4 is row-major (a1..a4 is the first row); glm is column-major.
    glm::dmat4 g;
    for (unsigned row = 0; row < 4; ++row)
        for (unsigned col = 0; col < 4; ++col) g[static_cast<int>(col)][static_cast<int>(row)] = static_cast<double>(m[row][col]);
    return g;
}

glm::dmat4 to_glm(const std::array<double, 16>& m) {
    glm::dmat4 g;
    for (int row = 0; row < 4; ++row)
        for (int col = 0; col < 4; ++col) g[col][row] = m[static_cast<std::size_t>(row * 4 + col)];
    return g;
}

glm::dvec3 apply(const glm::dmat4& m, const glm::dvec3& p) { return glm::dvec3(m * glm::dvec4(p, 1.0)); }

std::string mesh_label(const aiMesh& mesh, unsigned index) {
    std::string label = "mesh " + std::to_string(index);
    if (mesh.mName.length > 0) label += " ('" + std::string(mesh.mName.C_Str()) + "')";
    return label;
}

void check_bounds(const std::filesystem::path& path, const Failure& fail) {
    if (!has_bounds(path)) return;
    const std::string file = read_input_file(path, "model file", std::uint64_t{1} << 40);
    if (const std::string problem = model_bounds_problem(path, file); !problem.empty()) fail(problem);
}

// Before Assimp triangulates: every face must have indices, all in range, and
// each mesh's primitive-type flags must match its faces. Assimp's triangulation
// asserts (aborts, in Debian's build) where they do not.
void check_faces_for_triangulation(aiScene& scene, const Failure& fail) {
    for (unsigned m = 0; m < scene.mNumMeshes; ++m) {
        aiMesh* mesh = scene.mMeshes[m];
        if (!mesh) fail("mesh " + std::to_string(m) + " missing");
        const std::string label = mesh_label(*mesh, m);
        if (mesh->mNumFaces > 0 && !mesh->mFaces) fail(label + ": faces missing");
        unsigned types = 0;
        for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
            const aiFace& face = mesh->mFaces[f];
            if (face.mNumIndices == 0 || !face.mIndices) fail(label + ": face " + std::to_string(f) + " has no indices");
            for (unsigned k = 0; k < face.mNumIndices; ++k)
                if (face.mIndices[k] >= mesh->mNumVertices)
                    fail(label + ": face " + std::to_string(f) + ": vertex index " + std::to_string(face.mIndices[k]) +
                         " out of range (" + std::to_string(mesh->mNumVertices) + " vertices)");
            types |= face.mNumIndices == 1   ? aiPrimitiveType_POINT
                     : face.mNumIndices == 2 ? aiPrimitiveType_LINE
                     : face.mNumIndices == 3 ? aiPrimitiveType_TRIANGLE
                                             : aiPrimitiveType_POLYGON;
        }
        mesh->mPrimitiveTypes = types;
    }
}

// Material libraries and the like that a file names but that are not there.
// Assimp looks for each under several spellings of its path: one name each.
// Names in `refused` (files outside the model's folder) are left out: such a
// file is reported as refused, not also as missing under another spelling.
std::string missing_file_names(const std::filesystem::path& model, const std::vector<std::string>& missing,
                               const std::vector<std::string>& refused = {}) {
    std::vector<std::string> names, refused_names;
    for (const std::string& r : refused) refused_names.push_back(std::filesystem::path(r).filename().string());
    std::vector<std::string> all = missing;
    all.insert(all.end(), refused.begin(), refused.end());
    for (const std::string& m : all) {
        const std::string name = std::filesystem::path(m).filename().string();
        if (!name.empty() && name != model.filename().string() && std::find(names.begin(), names.end(), name) == names.end())
            names.push_back(name);
    }
    // Every name a path holds: a cut-off spelling of one ("gone." for "gone.mtl",
    // "kdrt-te" for a folder "kdrt-test") is no file of its own.
    std::vector<std::string> parts;
    all.push_back(model.string());
    for (const std::string& m : all)
        for (const std::filesystem::path& part : std::filesystem::path(m)) parts.push_back(part.string());
    std::string list;
    for (const std::string& name : names) {
        const bool prefix = std::any_of(parts.begin(), parts.end(), [&](const std::string& other) {
            return other.size() > name.size() && other.compare(0, name.size(), name) == 0;
        });
        const bool was_refused = std::find(refused_names.begin(), refused_names.end(), name) != refused_names.end();
        if (!prefix && !was_refused) list += (list.empty() ? "" : ", ") + name;
    }
    return list;
}

constexpr const char* kOutsideFilesHint =
    "ImportOptions::allow_outside_files, kdrt-render --allow-outside-files, allows them";

const aiScene* read_with_assimp(Assimp::Importer& importer, const std::filesystem::path& path,
                                const RegularFileIo& io, const Failure& fail) {
    const AssimpLogCapture log;
    // Skeleton-only files would otherwise get made-up bone geometry.
    importer.SetPropertyBool(AI_CONFIG_IMPORT_NO_SKELETON_MESHES, true);
    const aiScene* scene = nullptr;
    std::string problem;
    try {
        // Two steps, so that the faces are checked before Assimp triangulates them.
        scene = importer.ReadFile(path.string(), aiProcess_ValidateDataStructure);
        if (scene) {
            check_faces_for_triangulation(*const_cast<aiScene*>(scene), fail);  // the importer's own copy
            scene = importer.ApplyPostProcessing(aiProcess_Triangulate | aiProcess_ValidateDataStructure);
        }
        if (!scene) problem = importer.GetErrorString();
    } catch (const Error&) {
        throw;
    } catch (const std::bad_alloc&) {
        fail("out of memory while reading", ErrorCode::ResourceLimit);
    } catch (const std::exception& e) {
        problem = e.what();
    }
    if (scene) {
        // What Assimp repaired by dropping data is an error here: the picture would be silently wrong.
        for (const std::string& message : log.messages())
            if (message.find("out-of-range") != std::string::npos || message.find("out of range") != std::string::npos)
                fail("cannot import: " + message);
        return scene;
    }
    // Assimp catches an exhausted memory itself and reports it as text.
    if (problem.find("bad_alloc") != std::string::npos) fail("out of memory while reading", ErrorCode::ResourceLimit);
    if (problem.empty() || problem.find("No suitable reader") != std::string::npos)
        problem = "not a valid ." + lower_extension(path) + " file (no Assimp reader accepts it: corrupt or truncated?)";
    if (const std::string refused = missing_file_names(path, io.refused()); !refused.empty())
        problem += " (it names files outside the model's folder, not read: " + refused + "; " + kOutsideFilesHint + ")";
    fail("cannot import: " + problem);
}

// The global transform of every node, by name, for the cameras and lights
// that refer to nodes by name (the first node of a name wins).
using NodeTransforms = std::map<std::string, glm::dmat4>;

struct MeshBuilder {
    const aiScene& scene;
    const Failure& fail;
    ImportedModel& model;
    std::vector<int> material_of;  // aiScene material -> model material, -1 = unused so far

    MaterialId material(unsigned index) {
        if (index >= scene.mNumMaterials || !scene.mMaterials[index])
            fail("material index " + std::to_string(index) + " out of range (" + std::to_string(scene.mNumMaterials) +
                 " materials)");
        if (material_of[index] < 0) {
            material_of[index] = static_cast<int>(model.materials.size());
            Material m = whitted_material(*scene.mMaterials[index]);
            aiString name;
            if (scene.mMaterials[index]->Get(AI_MATKEY_NAME, name) == AI_SUCCESS && name.length > 0)
                m.name = name.C_Str();
            else
                m.name = "material" + std::to_string(index);
            model.materials.push_back(std::move(m));
        }
        return static_cast<MaterialId>(material_of[index]);
    }

    // Appends one placed instance of a mesh.
    void add(unsigned mesh_index, const glm::dmat4& to_world) {
        if (mesh_index >= scene.mNumMeshes || !scene.mMeshes[mesh_index])
            fail("node refers to mesh " + std::to_string(mesh_index) + " out of range (" +
                 std::to_string(scene.mNumMeshes) + " meshes)");
        const aiMesh& mesh = *scene.mMeshes[mesh_index];
        const std::string label = mesh_label(mesh, mesh_index);
        if (mesh.mNumVertices > 0 && !mesh.mVertices) fail(label + ": vertex positions missing");
        if (mesh.mNumFaces > 0 && !mesh.mFaces) fail(label + ": faces missing");
        Mesh& out = model.mesh;
        if (out.positions.size() + mesh.mNumVertices >= kNoNormal)
            fail("too many vertices (more than 2^32 - 1 after instancing)");
        const auto base = static_cast<std::uint32_t>(out.positions.size());
        const MaterialId mat = material(mesh.mMaterialIndex);
        ++model.stats.meshes;

        for (unsigned i = 0; i < mesh.mNumVertices; ++i) {
            const glm::dvec3 p = to_glm(mesh.mVertices[i]);
            if (!finite(p)) fail(label + ": vertex " + std::to_string(i) + ": position is not finite");
            const glm::dvec3 q = apply(to_world, p);
            if (!finite(q)) fail(label + ": vertex " + std::to_string(i) + ": position is not finite after the transform");
            out.positions.push_back(q);
            model.bounds.extend(q);
        }
        // Vertex normals share the vertices' indices; a zero one (common at
        // degenerate vertices) makes its triangles use the geometric normal.
        std::vector<bool> usable_normal;
        std::uint32_t normal_base = 0;
        if (mesh.mNormals && mesh.mNumVertices > 0) {
            normal_base = static_cast<std::uint32_t>(out.normals.size());
            const glm::dmat3 normal_matrix = glm::inverseTranspose(glm::dmat3(to_world));
            usable_normal.resize(mesh.mNumVertices);
            for (unsigned i = 0; i < mesh.mNumVertices; ++i) {
                const glm::dvec3 n = to_glm(mesh.mNormals[i]);
                if (!finite(n)) fail(label + ": vertex " + std::to_string(i) + ": normal is not finite");
                const glm::dvec3 m = normal_matrix * n;
                const double length = glm::length(m);
                usable_normal[i] = length > 0.0 && std::isfinite(length);
                out.normals.push_back(usable_normal[i] ? m / length : glm::dvec3(0.0, 0.0, 1.0));
            }
        }

        for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
            const aiFace& face = mesh.mFaces[f];
            if (face.mNumIndices == 1) { ++model.stats.skipped_points; continue; }
            if (face.mNumIndices == 2) { ++model.stats.skipped_lines; continue; }
            if (face.mNumIndices != 3 || !face.mIndices)
                fail(label + ": face " + std::to_string(f) + " has " + std::to_string(face.mNumIndices) +
                     " indices (expected 1, 2 or 3 after triangulation)");
            MeshTriangle t;
            bool normals = !usable_normal.empty();
            for (int k = 0; k < 3; ++k) {
                const unsigned v = face.mIndices[k];
                if (v >= mesh.mNumVertices)
                    fail(label + ": face " + std::to_string(f) + ": vertex index " + std::to_string(v) +
                         " out of range (" + std::to_string(mesh.mNumVertices) + " vertices)");
                t.v[static_cast<std::size_t>(k)] = base + v;
                normals = normals && usable_normal[v];
            }
            if (normals) {
                for (int k = 0; k < 3; ++k) t.n[static_cast<std::size_t>(k)] = normal_base + face.mIndices[k];
            } else if (!usable_normal.empty()) {
                ++model.stats.flat_triangles;
            }
            t.material = mat;
            if (out.triangles.size() >= kMaxTriangles)
                fail("too many triangles (more than 2^30 - 1 after instancing)");
            out.triangles.push_back(t);
        }
    }
};

// Depth-first, parents before children, children and meshes in file order:
// the triangle order (and so the object ids) of docs/IMPORT.md. Calls
// visit(node, its global transform); polls options.keep_going now and then.
template <class Visit>
void for_each_node(const aiScene& scene, const glm::dmat4& user, const ImportOptions& options, const Failure& fail,
                   Visit&& visit) {
    if (!scene.mRootNode) fail("no node tree");
    std::vector<std::pair<const aiNode*, glm::dmat4>> stack{{scene.mRootNode, user}};
    std::size_t visited = 0;
    while (!stack.empty()) {
        auto [node, parent] = stack.back();
        stack.pop_back();
        if (++visited > (std::size_t{1} << 26)) fail("node tree too large or cyclic");
        if (visited % 4096 == 0 && options.keep_going && !options.keep_going()) fail("import cancelled", ErrorCode::Cancelled);
        const glm::dmat4 global = parent * to_glm(node->mTransformation);
        if (node->mNumMeshes > 0 && !node->mMeshes) fail("node '" + std::string(node->mName.C_Str()) + "': meshes missing");
        visit(*node, global);
        if (node->mNumChildren > 0 && !node->mChildren)
            fail("node '" + std::string(node->mName.C_Str()) + "': children missing");
        for (unsigned i = node->mNumChildren; i-- > 0;)
            if (node->mChildren[i]) stack.emplace_back(node->mChildren[i], global);
    }
}

// The vertices, normals and triangles every instance of every mesh adds, so
// that the mesh is allocated once (growing it by each instance's size copied
// it once per instance: quadratic in the instances) and a model beyond
// FORMAT.md's limits is refused before anything is allocated.
void reserve_for_instances(const aiScene& scene, const ImportOptions& options, const Failure& fail, Mesh& out) {
    std::vector<std::uint64_t> triangles_of(scene.mNumMeshes, ~0ull);
    std::uint64_t vertices = 0, normals = 0, triangles = 0;
    for_each_node(scene, glm::dmat4(1.0), options, fail, [&](const aiNode& node, const glm::dmat4&) {
        for (unsigned i = 0; i < node.mNumMeshes; ++i) {
            const unsigned m = node.mMeshes[i];
            if (m >= scene.mNumMeshes || !scene.mMeshes[m]) continue;  // MeshBuilder::add names it
            const aiMesh& mesh = *scene.mMeshes[m];
            if (triangles_of[m] == ~0ull) {
                triangles_of[m] = 0;
                for (unsigned f = 0; mesh.mFaces && f < mesh.mNumFaces; ++f) triangles_of[m] += mesh.mFaces[f].mNumIndices == 3;
            }
            vertices += mesh.mNumVertices;
            normals += mesh.mNormals ? mesh.mNumVertices : 0;
            triangles += triangles_of[m];
        }
    });
    if (vertices >= kNoNormal) fail("too many vertices (more than 2^32 - 1 after instancing)");
    if (triangles > kMaxTriangles) fail("too many triangles (more than 2^30 - 1 after instancing)");
    out.positions.reserve(vertices);
    out.normals.reserve(normals);
    out.triangles.reserve(triangles);
}

// Builds the mesh; returns the global transform of every node by name.
NodeTransforms walk_nodes(const aiScene& scene, const glm::dmat4& user, const ImportOptions& options,
                          MeshBuilder& builder, const Failure& fail) {
    reserve_for_instances(scene, options, fail, builder.model.mesh);
    NodeTransforms transforms;
    for_each_node(scene, user, options, fail, [&](const aiNode& node, const glm::dmat4& global) {
        transforms.emplace(node.mName.C_Str(), global);
        for (unsigned i = 0; i < node.mNumMeshes; ++i) builder.add(node.mMeshes[i], global);
    });
    return transforms;
}

glm::dmat4 node_transform(const NodeTransforms& transforms, const aiString& name, const glm::dmat4& user) {
    auto it = transforms.find(name.C_Str());
    return it == transforms.end() ? user : it->second;
}

// Assimp's aiCamera keeps a horizontal field of view. Its glTF importer
// stores yfov * aspectRatio there, which is undone exactly; other importers
// store the true horizontal angle.
double vertical_fov_degrees(const aiCamera& c, bool gltf) {
    const double h = c.mHorizontalFOV;
    const double aspect = c.mAspect > 0.0f ? c.mAspect : 1.0;
    const double v = gltf ? h / aspect : 2.0 * std::atan(std::tan(h / 2.0) / aspect);
    return v * 180.0 / kPi;
}

void add_cameras(const aiScene& scene, const NodeTransforms& transforms, const glm::dmat4& user, bool gltf,
                 ImportedModel& model) {
    for (unsigned i = 0; i < scene.mNumCameras; ++i) {
        const aiCamera* c = scene.mCameras[i];
        if (!c) continue;
        const glm::dmat4 m = node_transform(transforms, c->mName, user);
        ModelCamera out;
        out.name = c->mName.C_Str();
        // A glTF camera sits at its node's origin; Assimp 5.2 also copies the
        // node's translation into mPosition, which would apply it twice.
        out.camera.position = apply(m, gltf ? glm::dvec3(0.0) : to_glm(c->mPosition));
        const glm::dvec3 direction = glm::dmat3(m) * to_glm(c->mLookAt);
        // Only the direction matters; step far enough that look_at differs from position in doubles.
        const double step = std::max({1.0, glm::length(out.camera.position), glm::length(model.bounds.extent())});
        out.camera.look_at = out.camera.position + step * glm::normalize(direction);
        out.camera.up = glm::dmat3(m) * to_glm(c->mUp);
        out.camera.fov_y = vertical_fov_degrees(*c, gltf);
        out.aspect = c->mAspect > 0.0f && std::isfinite(c->mAspect) ? c->mAspect : 0.0;
        // A perspective camera with a field of view of 0 or less is a bad camera, not an orthographic one.
        out.orthographic = c->mOrthographicWidth > 0.0f;
        model.cameras.push_back(std::move(out));
    }
}

// docs/IMPORT.md, "Lights": point and spot lights become point lights at
// their position, directional lights point lights far away against their
// direction; colours keep their ratios but are scaled so that no channel of
// any light exceeds 1 (kdrt's lights have no fall-off, so physical
// intensities mean nothing to it).
void add_lights(const aiScene& scene, const NodeTransforms& transforms, const glm::dmat4& user, const Failure& fail,
                ImportedModel& model) {
    const glm::dvec3 centre = model.bounds.empty() ? glm::dvec3(0.0) : (model.bounds.lo + model.bounds.hi) * 0.5;
    const double radius = model.bounds.empty() ? 1.0 : std::max(0.5 * glm::length(model.bounds.extent()), 1e-300);
    double brightest = 1.0;
    for (unsigned i = 0; i < scene.mNumLights; ++i) {
        const aiLight* l = scene.mLights[i];
        if (!l) continue;
        const glm::dmat4 m = node_transform(transforms, l->mName, user);
        PointLight out;
        out.color = glm::max(glm::dvec3(l->mColorDiffuse.r, l->mColorDiffuse.g, l->mColorDiffuse.b), glm::dvec3(0.0));
        switch (l->mType) {
            case aiLightSource_POINT:
            case aiLightSource_SPOT:
                out.position = apply(m, to_glm(l->mPosition));
                break;
            case aiLightSource_DIRECTIONAL: {
                const glm::dvec3 d = glm::dmat3(m) * to_glm(l->mDirection);
                out.position = centre - glm::normalize(d) * (1000.0 * radius);
                break;
            }
            default:
                ++model.stats.skipped_lights;
                continue;
        }
        if (!finite(out.position) || !finite(out.color))
            fail("light " + std::to_string(i) + " ('" + std::string(l->mName.C_Str()) + "'): position or colour is not finite");
        brightest = std::max({brightest, out.color.x, out.color.y, out.color.z});
        model.lights.push_back(out);
    }
    for (PointLight& l : model.lights) l.color /= brightest;
}

// "<file name>:<material name>", with "#2", "#3"... where names repeat.
void name_materials(const std::filesystem::path& path, std::vector<Material>& materials) {
    std::map<std::string, int> seen;
    for (Material& m : materials) {
        std::string name = path.filename().string() + ":" + m.name;
        int& count = seen[name];
        m.name = ++count == 1 ? name : name + "#" + std::to_string(count);
    }
}

}  // namespace

bool has_bounds(const std::filesystem::path& path) {
    const std::string ext = lower_extension(path);
    return ext == "ply" || ext == "off" || ext == "gltf" || ext == "glb" || ext == "fbx";
}

std::string model_bounds_problem(const std::filesystem::path& path, std::string_view file) {
    const std::string ext = lower_extension(path);
    const std::string head(file.substr(0, kHeaderLimit));
    if (ext == "ply") {
        std::string problem = ply_header_problem(head, file.size());
        return problem.empty() ? ply_body_problem(file) : problem;
    }
    if (ext == "off") return off_header_problem(head, file.size());
    if (ext == "fbx") return fbx_bounds_problem(file);
    if (ext == "gltf" || ext == "glb") return gltf_bounds_problem(file, ext == "glb", path.parent_path());
    return {};
}

ImportedModel import_with_assimp(const std::filesystem::path& path, const std::array<double, 16>& transform,
                                 const ImportOptions& options) {
    const Failure fail(path);
    check_bounds(path, fail);

    Assimp::Importer importer;
    auto* io = new RegularFileIo(path, options.allow_outside_files);  // owned by the importer
    importer.SetIOHandler(io);
    const aiScene* scene = read_with_assimp(importer, path, *io, fail);

    ImportedModel model;
    try {
        const glm::dmat4 user = to_glm(transform);
        MeshBuilder builder{*scene, fail, model, std::vector<int>(scene->mNumMaterials, -1)};
        const NodeTransforms transforms = walk_nodes(*scene, user, options, builder, fail);
        if (model.mesh.triangles.empty())
            fail("no triangles (" + std::to_string(model.stats.skipped_points) + " points and " +
                 std::to_string(model.stats.skipped_lines) + " lines skipped; kdrt renders triangles only)");
        const std::string ext = lower_extension(path);
        add_cameras(*scene, transforms, user, ext == "gltf" || ext == "glb", model);
        add_lights(*scene, transforms, user, fail, model);
    } catch (const std::bad_alloc&) {
        fail("out of memory while converting the model", ErrorCode::ResourceLimit);
    }
    name_materials(path, model.materials);

    if (const std::string missing = missing_file_names(path, io->missing(), io->refused()); !missing.empty())
        model.stats.warnings.push_back(path.string() + ": referenced files not found (" + missing +
                                       "): what they hold, such as materials, is missing");
    if (const std::string refused = missing_file_names(path, io->refused()); !refused.empty())
        model.stats.warnings.push_back(path.string() + ": referenced files outside the model's folder not read (" +
                                       refused + "; " + kOutsideFilesHint + ")");
    model.stats.triangles = model.mesh.triangles.size();
    model.stats.materials = model.materials.size();
    model.stats.cameras = model.cameras.size();
    model.stats.lights = model.lights.size();
    return model;
}

}  // namespace kdrt::detail
