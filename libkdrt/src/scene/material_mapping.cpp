// docs/IMPORT.md, "Materials": the mapping from Assimp's material keys to
// FORMAT.md's Whitted material (colour C, kd, ks, n, kr, kt, ior).
//
// Two families of files describe materials differently:
//  - glTF 2.0 (metallic-roughness PBR, Khronos 2017): base colour, metallic
//    m and roughness r, KHR_materials_transmission and KHR_materials_ior;
//  - Phong-style files (MTL and most others): Kd, Ks, Ns, d/Tr, Ni, and for
//    MTL the illumination model `illum` that switches reflection on.
// Textures are ignored throughout: only the constant factors are read.
#include "scene/material_mapping.h"

#include <assimp/GltfMaterial.h>
#include <assimp/ObjMaterial.h>
#include <assimp/material.h>

#include <glm/common.hpp>

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>

namespace kdrt::detail {
namespace {

constexpr double kMinShininess = 1.0;
constexpr double kMaxShininess = 10000.0;

std::optional<double> number(const aiMaterial& m, const char* key, unsigned type, unsigned index) {
    ai_real v = 0;
    if (m.Get(key, type, index, v) != AI_SUCCESS || !std::isfinite(static_cast<double>(v))) return std::nullopt;
    return static_cast<double>(v);
}

std::optional<int> integer(const aiMaterial& m, const char* key, unsigned type, unsigned index) {
    int v = 0;
    if (m.Get(key, type, index, v) != AI_SUCCESS) return std::nullopt;
    return v;
}

// Colours are clamped to >= 0: a negative reflectance has no meaning.
std::optional<glm::dvec3> colour(const aiMaterial& m, const char* key, unsigned type, unsigned index) {
    aiColor4D c(0, 0, 0, 1);
    if (m.Get(key, type, index, c) != AI_SUCCESS) return std::nullopt;
    glm::dvec3 v{c.r, c.g, c.b};
    if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z)) return std::nullopt;
    return glm::max(v, glm::dvec3(0.0));
}

bool has(const aiMaterial& m, const char* key, unsigned type, unsigned index) {
    const aiMaterialProperty* p = nullptr;
    return aiGetMaterialProperty(&m, key, type, index, &p) == AI_SUCCESS;
}

// Rec. 709 luminance: one weight from a specular or reflective colour.
double luminance(const glm::dvec3& c) { return 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z; }

double unit(double v) { return std::clamp(v, 0.0, 1.0); }

double shininess(double n) { return std::clamp(n, kMinShininess, kMaxShininess); }

// glTF metallic-roughness. Roughness r is perceptual: the microfacet width is
// alpha = r^2, and a Blinn-Phong lobe of exponent 2 / alpha^2 - 2 has about
// the same width (Walter et al. 2007, "Microfacet models for refraction
// through rough surfaces", section 5.2).
Material from_metallic_roughness(const aiMaterial& src) {
    Material out;
    out.color = colour(src, AI_MATKEY_BASE_COLOR).value_or(colour(src, AI_MATKEY_COLOR_DIFFUSE).value_or(glm::dvec3(1.0)));
    const double metallic = unit(number(src, AI_MATKEY_METALLIC_FACTOR).value_or(1.0));
    double roughness = unit(number(src, AI_MATKEY_ROUGHNESS_FACTOR).value_or(1.0));
    double ks_weight = 0.5 * (1.0 - metallic);
    // KHR_materials_pbrSpecularGlossiness: a diffuse colour and glossiness g = 1 - r.
    if (auto gloss = number(src, AI_MATKEY_GLOSSINESS_FACTOR)) {
        out.color = colour(src, AI_MATKEY_COLOR_DIFFUSE).value_or(out.color);
        roughness = 1.0 - unit(*gloss);
        ks_weight = unit(luminance(colour(src, AI_MATKEY_COLOR_SPECULAR).value_or(glm::dvec3(0.0))));
        out.reflect = 0.0;
    } else {
        out.reflect = metallic * (1.0 - roughness);  // smooth metals are mirrors, rough ones diffuse
    }
    const double alpha = std::max(roughness * roughness, 1e-4);
    out.shininess = shininess(2.0 / (alpha * alpha) - 2.0);
    out.specular = ks_weight * (1.0 - roughness);

    const double ior = number(src, AI_MATKEY_REFRACTI).value_or(1.5);  // KHR_materials_ior, default 1.5
    out.ior = ior > 0.0 ? ior : 1.5;
    aiString alpha_mode;
    const double opacity = unit(number(src, AI_MATKEY_OPACITY).value_or(1.0));
    if (auto transmission = number(src, AI_MATKEY_TRANSMISSION_FACTOR)) {
        out.transmit = unit(*transmission) * (1.0 - metallic);
    } else if (src.Get(AI_MATKEY_GLTF_ALPHAMODE, alpha_mode) == AI_SUCCESS &&
               std::string(alpha_mode.C_Str()) == "BLEND" && opacity < 1.0) {
        // alphaMode BLEND: a see-through surface that does not bend light.
        out.transmit = 1.0 - opacity;
        out.ior = 1.0;
    }
    out.reflect = std::min(out.reflect, 1.0 - out.transmit);
    out.diffuse = std::max(0.0, 1.0 - out.reflect - out.transmit);

    int mode = 0;
    if (src.Get(AI_MATKEY_SHADING_MODEL, mode) == AI_SUCCESS && mode == aiShadingMode_Unlit) {
        // KHR_materials_unlit: kdrt has no emission; the nearest is plain Lambert.
        out.diffuse = 1.0;
        out.specular = out.reflect = out.transmit = 0.0;
    }
    return out;
}

// MTL (Wavefront, "mtl" file format) and the generic Phong-style keys.
Material from_phong(const aiMaterial& src) {
    Material out;
    out.color = colour(src, AI_MATKEY_COLOR_DIFFUSE).value_or(glm::dvec3(1.0));
    const glm::dvec3 ks = colour(src, AI_MATKEY_COLOR_SPECULAR).value_or(glm::dvec3(0.0));
    const double strength = std::max(0.0, number(src, AI_MATKEY_SHININESS_STRENGTH).value_or(1.0));
    // Assimp's convention: an exponent of 0 (or none) means no highlight; its
    // STL and PLY readers give a white specular colour without one.
    const double exponent = number(src, AI_MATKEY_SHININESS).value_or(0.0);
    out.specular = exponent > 0.0 ? luminance(ks) * strength : 0.0;
    out.shininess = shininess(exponent);
    // d (dissolve) or 1 - Tr: the share of light that passes.
    const double opacity = unit(number(src, AI_MATKEY_OPACITY).value_or(1.0));
    out.transmit = 1.0 - opacity;
    const double ior = number(src, AI_MATKEY_REFRACTI).value_or(1.0);
    out.ior = ior > 0.0 ? ior : 1.0;  // MTL's Ni: 1 (no bending) when absent
    if (auto illum = integer(src, AI_MATKEY_OBJ_ILLUM)) {
        // illum 0 and 1 have no highlight; 3 to 8 trace the mirror ray weighted by Ks.
        if (*illum < 2) out.specular = 0.0;
        if (*illum >= 3 && *illum <= 8) out.reflect = unit(luminance(ks));
    } else if (auto reflectivity = number(src, AI_MATKEY_REFLECTIVITY); reflectivity && has(src, AI_MATKEY_COLOR_REFLECTIVE)) {
        // Collada and FBX: a reflective colour scaled by a reflectivity.
        out.reflect = unit(*reflectivity * luminance(colour(src, AI_MATKEY_COLOR_REFLECTIVE).value_or(glm::dvec3(0.0))));
    }
    out.reflect = std::min(out.reflect, 1.0 - out.transmit);
    out.diffuse = opacity;  // a dissolved surface shows that much less of its own colour
    return out;
}

bool is_metallic_roughness(const aiMaterial& src) {
    int mode = 0;
    if (src.Get(AI_MATKEY_SHADING_MODEL, mode) == AI_SUCCESS && mode == aiShadingMode_PBR_BRDF) return true;
    return has(src, AI_MATKEY_GLTF_ALPHAMODE);
}

}  // namespace

Material whitted_material(const aiMaterial& source) {
    return is_metallic_roughness(source) ? from_metallic_roughness(source) : from_phong(source);
}

}  // namespace kdrt::detail
