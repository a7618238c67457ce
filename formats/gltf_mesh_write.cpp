// gltf_mesh_write.cpp - see gltf_mesh_write.h. Only the glTF container is built here; which
// vertex gets which joints and weights, and what is quantized, comes from src/mesh.c.
#include "tinygltf_config.h"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <sstream>
#include <string>
#include <vector>

extern "C" {
#include "internal/atomic_file.h"
}
#include "crowdbake/gltf_mesh_write.h"

namespace {

struct Writer {
    tinygltf::Model g;
    std::vector<unsigned char> &bin() { return g.buffers[0].data; }

    // A buffer view of `bytes` elements of `size` bytes each, each padded to 4 for vertex data.
    int view(const void *data, size_t count, size_t size, bool vertex)
    {
        size_t stride = vertex ? (size + 3) / 4 * 4 : size;
        while (bin().size() % 4) bin().push_back(0);
        tinygltf::BufferView v;
        v.buffer = 0;
        v.byteOffset = bin().size();
        v.byteLength = count * stride;
        if (vertex && stride != size) v.byteStride = stride;
        v.target = vertex ? TINYGLTF_TARGET_ARRAY_BUFFER : TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER;
        const unsigned char *src = static_cast<const unsigned char *>(data);
        for (size_t i = 0; i < count; ++i) {
            bin().insert(bin().end(), src + i * size, src + (i + 1) * size);
            bin().insert(bin().end(), stride - size, 0);
        }
        g.bufferViews.push_back(v);
        return (int)g.bufferViews.size() - 1;
    }

    int accessor(int view_index, size_t count, int component, int type, bool normalized)
    {
        tinygltf::Accessor a;
        a.bufferView = view_index;
        a.byteOffset = 0;
        a.count = count;
        a.componentType = component;
        a.type = type;
        a.normalized = normalized;
        g.accessors.push_back(a);
        return (int)g.accessors.size() - 1;
    }

    // What the parts look like, each material, texture and image written once, in the order
    // the parts first use them (so the bytes follow the model's primitive order alone).
    std::vector<const cb_material *> materials;
    std::vector<const cb_texture *> textures;
    std::vector<const cb_image *> images;

    // Plain data (inverse bind matrices, images): no target, no padding.
    int data_view(const void *data, size_t bytes)
    {
        while (bin().size() % 4) bin().push_back(0);
        tinygltf::BufferView v;
        v.buffer = 0;
        v.byteOffset = bin().size();
        v.byteLength = bytes;
        bin().insert(bin().end(), static_cast<const unsigned char *>(data), static_cast<const unsigned char *>(data) + bytes);
        g.bufferViews.push_back(v);
        return (int)g.bufferViews.size() - 1;
    }
};

template <class T> int index_of(std::vector<const T *> &list, const T *item)
{
    for (size_t i = 0; i < list.size(); ++i)
        if (list[i] == item) return (int)i;
    list.push_back(item);
    return (int)list.size() - 1;
}

// Only TEXCOORD_0 is carried, so a texture read through another set is left out (the colour
// factor stays).
tinygltf::Material material(Writer &w, const cb_material &m)
{
    tinygltf::Material out;
    out.name = m.name;
    out.pbrMetallicRoughness.baseColorFactor.assign(m.base_color, m.base_color + 4);
    out.pbrMetallicRoughness.metallicFactor = m.metallic;
    out.pbrMetallicRoughness.roughnessFactor = m.roughness;
    if (m.base_color_texture && m.base_color_texcoord == 0)
        out.pbrMetallicRoughness.baseColorTexture.index = index_of(w.textures, m.base_color_texture);
    static const char *const modes[] = {"OPAQUE", "MASK", "BLEND"};
    out.alphaMode = modes[m.alpha_mode <= CB_ALPHA_BLEND ? m.alpha_mode : 0];
    if (m.alpha_mode == CB_ALPHA_MASK) out.alphaCutoff = m.alpha_cutoff;
    out.doubleSided = m.double_sided;
    return out;
}

// An image's bytes: the model's, or its file's (read now: loading never reads image files).
bool image_bytes(const cb_image &im, std::vector<unsigned char> *out, std::string *why)
{
    if (im.bytes) {
        out->assign(im.bytes, im.bytes + im.size);
        return true;
    }
    FILE *f = std::fopen(im.path, "rb");
    if (!f) {
        *why = std::string(im.path) + ": cannot read the image a material uses (" + std::strerror(errno) +
               "); put it beside the model, where its uri says";
        return false;
    }
    unsigned char chunk[65536];
    size_t n;
    while ((n = std::fread(chunk, 1, sizeof chunk, f)) > 0) out->insert(out->end(), chunk, chunk + n);
    bool ok = !std::ferror(f) && !out->empty();
    std::fclose(f);
    if (!ok) *why = std::string(im.path) + ": the image a material uses is empty or unreadable; re-export it";
    return ok;
}

// glTF wants a type on an image in a bufferView, and a uri gives none.
std::string mime_type(const cb_image &im, const std::vector<unsigned char> &bytes)
{
    static const unsigned char png[4] = {0x89, 'P', 'N', 'G'}, jpeg[3] = {0xFF, 0xD8, 0xFF};
    if (im.mime_type && im.mime_type[0]) return im.mime_type;
    if (bytes.size() >= 4 && std::memcmp(bytes.data(), png, 4) == 0) return "image/png";
    if (bytes.size() >= 3 && std::memcmp(bytes.data(), jpeg, 3) == 0) return "image/jpeg";
    return "application/octet-stream";
}

// The textures, one sampler each, and their images embedded in the binary chunk.
bool add_textures(Writer &w, std::string *why)
{
    for (const cb_texture *t : w.textures) {
        tinygltf::Sampler s;
        s.magFilter = t->mag_filter ? t->mag_filter : -1;
        s.minFilter = t->min_filter ? t->min_filter : -1;
        s.wrapS = t->wrap_s, s.wrapT = t->wrap_t;
        w.g.samplers.push_back(s);
        tinygltf::Texture tex;
        tex.sampler = (int)w.g.samplers.size() - 1;
        tex.source = index_of(w.images, t->image);
        w.g.textures.push_back(tex);
    }
    for (const cb_image *im : w.images) {
        std::vector<unsigned char> bytes;
        if (!image_bytes(*im, &bytes, why)) return false;
        tinygltf::Image out;
        out.mimeType = mime_type(*im, bytes);
        out.bufferView = w.data_view(bytes.data(), bytes.size());
        w.g.images.push_back(out);
    }
    return true;
}

// The bind pose of a joint: the inverse of its inverse bind matrix (affine).
void invert_affine(const double m[16], double out[16])
{
    double a = m[0], b = m[4], c = m[8], d = m[1], e = m[5], f = m[9], g = m[2], h = m[6], i = m[10];
    double det = a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g);
    double inv[9] = {(e * i - f * h) / det, (c * h - b * i) / det, (b * f - c * e) / det,
                     (f * g - d * i) / det, (a * i - c * g) / det, (c * d - a * f) / det,
                     (d * h - e * g) / det, (b * g - a * h) / det, (a * e - b * d) / det}; // row-major
    for (int r = 0; r < 3; ++r) {
        for (int k = 0; k < 3; ++k) out[k * 4 + r] = inv[r * 3 + k];
        out[12 + r] = -(inv[r * 3] * m[12] + inv[r * 3 + 1] * m[13] + inv[r * 3 + 2] * m[14]);
        out[r * 4 + 3] = 0;
    }
    out[15] = 1;
}

void add_skeleton(Writer &w, const cb_model *pm, int32_t skin_index)
{
    const cb_skin &skin = pm->skins[skin_index];
    int root = (int)w.g.nodes.size();
    w.g.nodes.emplace_back();
    w.g.nodes[(size_t)root].name = "palette_bones";
    tinygltf::Skin s;
    s.name = "palette";
    s.skeleton = root;
    std::vector<float> ibm(skin.joint_count * 16);
    for (uint32_t j = 0; j < skin.joint_count; ++j) {
        tinygltf::Node n;
        n.name = pm->nodes[skin.joints[j]].name;
        double bind[16];
        invert_affine(skin.inverse_bind + j * 16, bind);
        n.matrix.assign(bind, bind + 16);
        for (int k = 0; k < 16; ++k) ibm[j * 16 + k] = (float)skin.inverse_bind[j * 16 + k];
        s.joints.push_back((int)w.g.nodes.size());
        w.g.nodes[(size_t)root].children.push_back((int)w.g.nodes.size());
        w.g.nodes.push_back(n);
    }
    s.inverseBindMatrices = w.accessor(w.data_view(ibm.data(), ibm.size() * 4), skin.joint_count, TINYGLTF_COMPONENT_TYPE_FLOAT,
                                       TINYGLTF_TYPE_MAT4, false);
    w.g.skins.push_back(s);
}

// TEXCOORD_n = (vertex id, 0) from `first_id` on, and zeros in the channels below n the part lacks
// (glTF wants texture coordinate sets numbered without gaps).
void add_vertex_id(Writer &w, uint32_t vertex_id_set, const cb_mesh_part &p, uint32_t first_id, tinygltf::Primitive &prim)
{
    size_t n = p.vertex_count;
    std::vector<float> ids(n * 2, 0.0f), zeros(n * 2, 0.0f);
    for (size_t v = 0; v < n; ++v) ids[v * 2] = (float)(first_id + v);
    for (uint32_t set = 0; set <= vertex_id_set; ++set) {
        std::string name = "TEXCOORD_" + std::to_string(set);
        if (prim.attributes.count(name)) continue;
        const std::vector<float> &data = set == vertex_id_set ? ids : zeros;
        prim.attributes[name] = w.accessor(w.view(data.data(), n, 8, true), n, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC2, false);
    }
}

// vertex_id_set < 0: no vertex-id channel.
void add_part(Writer &w, const cb_mesh *m, const cb_mesh_part &p, uint32_t first_id, int64_t vertex_id_set, tinygltf::Mesh &mesh)
{
    tinygltf::Primitive prim;
    prim.mode = TINYGLTF_MODE_TRIANGLES;
    size_t n = p.vertex_count;
    int pos = w.accessor(w.view(p.positions, n, 12, true), n, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, false);
    auto &acc = w.g.accessors[(size_t)pos];
    acc.minValues = {INFINITY, INFINITY, INFINITY};
    acc.maxValues = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t v = 0; v < n; ++v)
        for (int k = 0; k < 3; ++k) {
            acc.minValues[k] = std::fmin(acc.minValues[k], p.positions[v * 3 + k]);
            acc.maxValues[k] = std::fmax(acc.maxValues[k], p.positions[v * 3 + k]);
        }
    prim.attributes["POSITION"] = pos;
    if (p.normals_i8)
        prim.attributes["NORMAL"] = w.accessor(w.view(p.normals_i8, n, 3, true), n, TINYGLTF_COMPONENT_TYPE_BYTE, TINYGLTF_TYPE_VEC3, true);
    else if (p.normals)
        prim.attributes["NORMAL"] = w.accessor(w.view(p.normals, n, 12, true), n, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, false);
    if (p.texcoords_u16)
        prim.attributes["TEXCOORD_0"] =
            w.accessor(w.view(p.texcoords_u16, n, 4, true), n, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT, TINYGLTF_TYPE_VEC2, true);
    else if (p.texcoords)
        prim.attributes["TEXCOORD_0"] = w.accessor(w.view(p.texcoords, n, 8, true), n, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC2, false);
    if (m->bone_count <= 256) {
        std::vector<uint8_t> j8(n * 4);
        for (size_t i = 0; i < n * 4; ++i) j8[i] = (uint8_t)p.joints[i];
        prim.attributes["JOINTS_0"] = w.accessor(w.view(j8.data(), n, 4, true), n, TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, TINYGLTF_TYPE_VEC4, false);
    } else {
        prim.attributes["JOINTS_0"] = w.accessor(w.view(p.joints, n, 8, true), n, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT, TINYGLTF_TYPE_VEC4, false);
    }
    if (p.weights_q && m->weight_scale == 255) {
        std::vector<uint8_t> w8(p.weights_q, p.weights_q + n * 4);
        prim.attributes["WEIGHTS_0"] = w.accessor(w.view(w8.data(), n, 4, true), n, TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, TINYGLTF_TYPE_VEC4, true);
    } else if (p.weights_q) {
        prim.attributes["WEIGHTS_0"] = w.accessor(w.view(p.weights_q, n, 8, true), n, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT, TINYGLTF_TYPE_VEC4, true);
    } else {
        prim.attributes["WEIGHTS_0"] = w.accessor(w.view(p.weights, n, 16, true), n, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC4, false);
    }
    if (p.colors)
        prim.attributes["COLOR_0"] = w.accessor(w.view(p.colors, n, 16, true), n, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC4, false);
    if (p.material) prim.material = index_of(w.materials, p.material);
    if (vertex_id_set >= 0) add_vertex_id(w, (uint32_t)vertex_id_set, p, first_id, prim);
    if (p.instance_ids)
        prim.attributes[CB_INSTANCE_ID_ATTRIBUTE] =
            w.accessor(w.view(p.instance_ids, n, 4, true), n, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_SCALAR, false);
    if (n <= 65535) {
        std::vector<uint16_t> i16(p.indices, p.indices + p.index_count);
        prim.indices = w.accessor(w.view(i16.data(), p.index_count, 2, false), p.index_count,
                                  TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT, TINYGLTF_TYPE_SCALAR, false);
    } else {
        prim.indices = w.accessor(w.view(p.indices, p.index_count, 4, false), p.index_count,
                                  TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT, TINYGLTF_TYPE_SCALAR, false);
    }
    mesh.primitives.push_back(prim);
}

tinygltf::Value extras(const cb_mesh *m, const cb_mesh_error *e, int64_t vertex_id_set)
{
    tinygltf::Value::Object o;
    o["max_influences"] = tinygltf::Value((int)m->max_influences);
    o["quantized"] = tinygltf::Value(m->quantized);
    o["batch"] = tinygltf::Value((int)m->batch);
    if (m->batch > 1) o["instance_id_attribute"] = tinygltf::Value(std::string(CB_INSTANCE_ID_ATTRIBUTE));
    if (vertex_id_set >= 0) o["vertex_id_texcoord"] = tinygltf::Value((int)vertex_id_set);
    o["palette_bones"] = tinygltf::Value((int)m->bone_count);
    if (e) {
        o["error_mm_per_m"] = tinygltf::Value(e->max_mm_per_m);
        o["error_frames"] = tinygltf::Value((int)e->frames);
    }
    if (m->quantized) o["normal_error_degrees"] = tinygltf::Value(m->normal_error_deg);
    if (m->quantized) o["weight_bits"] = tinygltf::Value(m->weight_scale == 255 ? 8 : 16);
    tinygltf::Value::Object root;
    root["crowdbake"] = tinygltf::Value(o);
    return tinygltf::Value(root);
}

} // namespace

static cb_status write_mesh(const char *path, const cb_mesh *mesh, const cb_model *palette_model, int32_t palette_skin,
                     const cb_mesh_error *error, int64_t vertex_id_set, cb_error *err)
{
    Writer w;
    w.g.asset.version = "2.0";
    w.g.asset.generator = "crowdbake " CROWDBAKE_VERSION;
    w.g.asset.extras = extras(mesh, error, vertex_id_set);
    w.g.buffers.resize(1);
    add_skeleton(w, palette_model, palette_skin);
    tinygltf::Mesh m;
    m.name = "crowd_mesh";
    uint32_t first_id = 0;
    for (uint32_t i = 0; i < mesh->part_count; ++i) {
        add_part(w, mesh, mesh->parts[i], first_id, vertex_id_set, m);
        first_id += mesh->parts[i].vertex_count;
    }
    w.g.meshes.push_back(m);
    for (const cb_material *used : w.materials) w.g.materials.push_back(material(w, *used));
    std::string why;
    if (!add_textures(w, &why)) return cb_fail(err, CB_ERR_IO, "%s", why.c_str());
    tinygltf::Node node;
    node.name = "crowd_mesh";
    node.mesh = 0;
    node.skin = 0;
    w.g.nodes.push_back(node);
    tinygltf::Scene scene;
    scene.nodes = {0, (int)w.g.nodes.size() - 1};
    w.g.scenes.push_back(scene);
    w.g.defaultScene = 0;
    bool uses_quantization = false;
    for (uint32_t i = 0; i < mesh->part_count; ++i) uses_quantization |= mesh->parts[i].normals_i8 != nullptr;
    if (uses_quantization) {
        w.g.extensionsUsed.push_back("KHR_mesh_quantization");
        w.g.extensionsRequired.push_back("KHR_mesh_quantization");
    }
    std::ostringstream out;
    tinygltf::TinyGLTF writer;
    if (!writer.WriteGltfSceneToStream(&w.g, out, false, true))
        return cb_fail(err, CB_ERR_INTERNAL, "%s: tinygltf could not write the mesh", path);
    std::string bytes = out.str();
    cb_atomic_file f;
    if (cb_atomic_open(&f, path, err)) return err->status;
    if (cb_atomic_write(&f, bytes.data(), bytes.size(), err) || cb_atomic_commit(&f, err)) {
        cb_atomic_abort(&f);
        return err->status;
    }
    return CB_OK;
}

extern "C" cb_status cb_gltf_mesh_write(const char *path, const cb_mesh *mesh, const cb_model *palette_model,
                                        int32_t palette_skin, const cb_mesh_error *error, cb_error *err)
{
    return write_mesh(path, mesh, palette_model, palette_skin, error, -1, err);
}

extern "C" cb_status cb_gltf_mesh_write_vertex_ids(const char *path, const cb_mesh *mesh, const cb_model *palette_model,
                                                   int32_t palette_skin, const cb_mesh_error *error, uint32_t vertex_id_set,
                                                   cb_error *err)
{
    return write_mesh(path, mesh, palette_model, palette_skin, error, vertex_id_set, err);
}
