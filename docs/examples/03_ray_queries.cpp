// Ray queries on a scene loaded from a file: the closest hit of a grid of
// camera rays, then whether each hit point sees the first light.
#include <kdrt/committed_scene.h>
#include <kdrt/device.h>
#include <kdrt/ray_query.h>
#include <kdrt/scene_loader.h>

#include <glm/geometric.hpp>

#include <cstdint>
#include <cstdio>
#include <vector>

int main(int argc, char** argv) {
    kdrt::Scene scene = kdrt::load_scene(argc > 1 ? argv[1] : "scenes/2x2x4.json");
    kdrt::CommittedScene committed = kdrt::CommittedScene::commit(kdrt::Device::open(), scene);

    // An 8 x 8 fan of rays from the camera around its view direction.
    glm::vec3 eye(scene.camera.position);
    glm::vec3 forward = glm::normalize(glm::vec3(scene.camera.look_at) - eye);
    glm::vec3 right = glm::normalize(glm::cross(glm::vec3(scene.camera.up), forward));
    glm::vec3 up = glm::cross(forward, right);
    std::vector<kdrt::QueryRay> rays;
    for (int y = 0; y < 8; ++y) {
        for (int x = 0; x < 8; ++x) {
            glm::vec3 d = glm::normalize(forward + 0.05f * (x - 3.5f) * right + 0.05f * (y - 3.5f) * up);
            rays.push_back({{eye.x, eye.y, eye.z}, 0.0f, {d.x, d.y, d.z}, 1e30f});
        }
    }
    std::vector<kdrt::QueryHit> hits(rays.size());
    kdrt::intersect(committed, rays, hits);

    // Shadow rays from each hit towards the light: occluded on (t_min, t_max].
    glm::vec3 light(scene.lights.at(0).position);
    std::vector<kdrt::QueryRay> shadow_rays;
    for (std::size_t i = 0; i < hits.size(); ++i) {
        if (hits[i].object == KDRT_NO_HIT) continue;
        glm::vec3 o(rays[i].origin[0], rays[i].origin[1], rays[i].origin[2]);
        glm::vec3 d(rays[i].direction[0], rays[i].direction[1], rays[i].direction[2]);
        glm::vec3 normal(hits[i].normal[0], hits[i].normal[1], hits[i].normal[2]);
        glm::vec3 p = o + hits[i].t * d + 1e-3f * normal;  // step off the surface
        glm::vec3 to_light = light - p;
        float distance = glm::length(to_light);
        glm::vec3 l = to_light / distance;
        shadow_rays.push_back({{p.x, p.y, p.z}, 0.0f, {l.x, l.y, l.z}, distance});
    }
    std::vector<std::uint8_t> blocked(shadow_rays.size());
    kdrt::occluded(committed, shadow_rays, blocked);

    std::size_t in_shadow = 0;
    for (std::uint8_t b : blocked) in_shadow += b;
    std::printf("%zu rays, %zu hits, %zu hit points in shadow\n", rays.size(), shadow_rays.size(), in_shadow);

    // hit.object is the scene's object id: what Scene::add_* returned, or for
    // a loaded file FORMAT.md's numbering (spheres first, in file order).
    const kdrt::QueryHit& hit = hits[3 * 8 + 3];
    if (hit.kind == KDRT_KIND_SPHERE) {
        const kdrt::Sphere& sphere = scene.spheres.at(hit.object);
        std::printf("ray 27 hits sphere %u (centre %g %g %g) at t = %g\n", hit.object, sphere.center.x,
                    sphere.center.y, sphere.center.z, hit.t);
    }
    return shadow_rays.empty() ? 1 : 0;
}
