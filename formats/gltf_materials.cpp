// gltf_materials.cpp - what a primitive looks like (base colour, its texture and sampler, alpha
// mode, sides), kept from either parse so `crowdbake mesh` writes it back. Nothing here can fail
// a bake: a material part that cannot be read is left out, as the bake never draws.
#include <cstdio>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include "gltf_parts.h"

namespace cbgltf {

void materials_from_tinygltf(tinygltf::Model *g, doc::Document *out)
{
    for (const tinygltf::Material &m : g->materials) {
        doc::Material to;
        to.name = m.name;
        const tinygltf::PbrMetallicRoughness &pbr = m.pbrMetallicRoughness;
        for (size_t k = 0; k < 4 && k < pbr.baseColorFactor.size(); ++k) to.base_color[k] = pbr.baseColorFactor[k];
        to.metallic = pbr.metallicFactor, to.roughness = pbr.roughnessFactor;
        to.base_color_texture = pbr.baseColorTexture.index, to.base_color_texcoord = pbr.baseColorTexture.texCoord;
        to.alpha_mode = m.alphaMode, to.alpha_cutoff = m.alphaCutoff, to.double_sided = m.doubleSided;
        out->materials.push_back(std::move(to));
    }
    for (const tinygltf::Texture &t : g->textures) out->textures.push_back({t.source, t.sampler});
    for (tinygltf::Image &im : g->images) {
        doc::Image to;
        to.bufferView = im.bufferView;
        to.mimeType = im.mimeType;
        if (im.bufferView < 0) to.bytes = std::move(im.image); // a data uri's, kept raw by the loader's image callback
        if (im.bufferView < 0 && to.bytes.empty()) to.uri = im.uri;
        out->images.push_back(std::move(to));
    }
    for (const tinygltf::Sampler &s : g->samplers) out->samplers.push_back({s.magFilter, s.minFilter, s.wrapS, s.wrapT});
}

namespace {

// %XX escapes decoded, as glTF's uris are URI references.
std::string uri_decoded(const std::string &uri)
{
    std::string out;
    for (size_t i = 0; i < uri.size(); ++i) {
        unsigned code;
        if (uri[i] == '%' && i + 2 < uri.size() && std::sscanf(uri.c_str() + i + 1, "%2x", &code) == 1) {
            out += (char)code;
            i += 2;
        } else {
            out += uri[i];
        }
    }
    return out;
}

// The path of an image in a file beside the model, for `mesh` to read: a relative uri that stays
// inside the model's folder (the loader's rule for external files); "" for any other.
std::string image_path(const Context &c, const std::string &uri)
{
    std::string rel = uri_decoded(uri);
    if (rel.empty() || rel[0] == '/' || rel.find(':') != std::string::npos || rel.find('\0') != std::string::npos) return "";
    for (size_t start = 0;;) {
        size_t end = rel.find('/', start);
        if (rel.compare(start, end == std::string::npos ? std::string::npos : end - start, "..") == 0) return "";
        if (end == std::string::npos) break;
        start = end + 1;
    }
    std::string dir = c.name;
    size_t slash = dir.find_last_of('/');
    return slash == std::string::npos ? rel : dir.substr(0, slash + 1) + rel;
}

// The bytes of an image: its bufferView checked against its buffer, or what tinygltf decoded of
// its data uri. The model owns both (the buffers are the model's; uri bytes are copied).
bool image_bytes(Context &c, const doc::Image &im, cb_image *out)
{
    const doc::Document &g = *c.doc;
    if (im.bufferView < 0) {
        if (im.bytes.empty()) return false;
        void *copy = cb_model_alloc(c.model, im.bytes.size(), 1);
        if (!copy) return false;
        std::memcpy(copy, im.bytes.data(), im.bytes.size());
        out->bytes = static_cast<const unsigned char *>(copy);
        out->size = im.bytes.size();
        return true;
    }
    if ((size_t)im.bufferView >= g.bufferViews.size()) return false;
    const doc::BufferView &v = g.bufferViews[(size_t)im.bufferView];
    if (v.buffer < 0 || (size_t)v.buffer >= c.buffers.size()) return false;
    const Span &buf = c.buffers[(size_t)v.buffer];
    if (!buf.data || v.byteOffset > buf.size || v.byteLength > buf.size - v.byteOffset || v.byteLength == 0) return false;
    out->bytes = buf.data + v.byteOffset;
    out->size = v.byteLength;
    return true;
}

cb_alpha_mode alpha_mode(const std::string &s)
{
    return s == "MASK" ? CB_ALPHA_MASK : s == "BLEND" ? CB_ALPHA_BLEND : CB_ALPHA_OPAQUE;
}

bool convert_images(Context &c)
{
    const doc::Document &g = *c.doc;
    cb_model *m = c.model;
    if (g.images.empty()) return true;
    if (!(m->images = static_cast<cb_image *>(cb_model_alloc(m, g.images.size(), sizeof(cb_image))))) return false;
    m->image_count = (uint32_t)g.images.size();
    for (size_t i = 0; i < g.images.size(); ++i) {
        cb_image &to = m->images[i];
        if (!image_bytes(c, g.images[i], &to)) to.bytes = nullptr, to.size = 0;
        std::string path = to.bytes ? "" : image_path(c, g.images[i].uri);
        if (!path.empty() && !(to.path = cb_model_strdup(m, path.c_str()))) return false;
        to.mime_type = cb_model_strdup(m, g.images[i].mimeType.c_str());
        if (!to.mime_type) return false;
    }
    return true;
}

bool convert_textures(Context &c)
{
    const doc::Document &g = *c.doc;
    cb_model *m = c.model;
    if (g.textures.empty()) return true;
    if (!(m->textures = static_cast<cb_texture *>(cb_model_alloc(m, g.textures.size(), sizeof(cb_texture))))) return false;
    m->texture_count = (uint32_t)g.textures.size();
    for (size_t i = 0; i < g.textures.size(); ++i) {
        const doc::Texture &t = g.textures[i];
        cb_texture &to = m->textures[i];
        bool has_image = t.source >= 0 && (size_t)t.source < m->image_count && (m->images[t.source].bytes || m->images[t.source].path);
        to.image = has_image ? &m->images[t.source] : nullptr;
        doc::Sampler s;
        if (t.sampler >= 0 && (size_t)t.sampler < g.samplers.size()) s = g.samplers[(size_t)t.sampler];
        to.mag_filter = s.magFilter < 0 ? 0 : s.magFilter, to.min_filter = s.minFilter < 0 ? 0 : s.minFilter;
        to.wrap_s = s.wrapS, to.wrap_t = s.wrapT;
    }
    return true;
}

} // namespace

bool convert_materials(Context &c)
{
    const doc::Document &g = *c.doc;
    cb_model *m = c.model;
    bool ok = convert_images(c) && convert_textures(c);
    if (ok && !g.materials.empty()) {
        ok = (m->materials = static_cast<cb_material *>(cb_model_alloc(m, g.materials.size(), sizeof(cb_material))));
        if (ok) m->material_count = (uint32_t)g.materials.size();
    }
    for (size_t i = 0; ok && i < g.materials.size(); ++i) {
        const doc::Material &from = g.materials[i];
        cb_material &to = m->materials[i];
        ok = (to.name = cb_model_strdup(m, from.name.c_str()));
        for (int k = 0; k < 4; ++k) to.base_color[k] = (float)from.base_color[k];
        to.metallic = (float)from.metallic, to.roughness = (float)from.roughness;
        int t = from.base_color_texture;
        bool has_texture = t >= 0 && (size_t)t < m->texture_count && m->textures[t].image && from.base_color_texcoord >= 0;
        to.base_color_texture = has_texture ? &m->textures[t] : nullptr;
        to.base_color_texcoord = has_texture ? (uint32_t)from.base_color_texcoord : 0;
        to.alpha_mode = alpha_mode(from.alpha_mode);
        to.alpha_cutoff = (float)from.alpha_cutoff;
        to.double_sided = from.double_sided;
    }
    if (!ok) cb_fail(c.err, CB_ERR_INTERNAL, "%s: out of memory reading the materials", c.name);
    return ok;
}

} // namespace cbgltf
