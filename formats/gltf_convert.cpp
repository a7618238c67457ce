// gltf_convert.cpp - accessors read with bounds checks (in place where their floats allow),
// and the nodes, skins, meshes and animations converted to the core's structs.
#include <meshoptimizer.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <thread>
#include <type_traits>
#include <utility>
#include <fcntl.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>
#include <vector>

#include "gltf_parts.h"

namespace cbgltf {

// ---- the tinygltf path's Model as a doc::Document ----

void doc_from_tinygltf(tinygltf::Model *g, doc::Document *out)
{
    doc::Document d;
    d.extensionsRequired = g->extensionsRequired;
    for (tinygltf::Buffer &b : g->buffers) d.buffers.push_back(std::move(b.data));
    for (const tinygltf::BufferView &v : g->bufferViews) d.bufferViews.push_back({v.buffer, v.byteOffset, v.byteLength, v.byteStride});
    d.accessors.resize(g->accessors.size());
    for (size_t i = 0; i < g->accessors.size(); ++i) {
        const tinygltf::Accessor &a = g->accessors[i];
        doc::Accessor &to = d.accessors[i];
        to.bufferView = a.bufferView, to.byteOffset = a.byteOffset, to.normalized = a.normalized;
        to.componentType = a.componentType, to.count = a.count, to.type = a.type;
        to.sparse.isSparse = a.sparse.isSparse;
        if (!a.sparse.isSparse) continue; // tinygltf leaves the rest uninitialized
        to.sparse.count = a.sparse.count;
        to.sparse.indices.byteOffset = a.sparse.indices.byteOffset, to.sparse.indices.bufferView = a.sparse.indices.bufferView;
        to.sparse.indices.componentType = a.sparse.indices.componentType;
        to.sparse.values.bufferView = a.sparse.values.bufferView, to.sparse.values.byteOffset = a.sparse.values.byteOffset;
    }
    for (const tinygltf::Mesh &m : g->meshes) {
        d.meshes.emplace_back();
        for (const tinygltf::Primitive &p : m.primitives) {
            doc::Primitive to;
            to.attributes.assign(p.attributes.begin(), p.attributes.end());
            to.indices = p.indices;
            to.material = p.material;
            d.meshes.back().primitives.push_back(std::move(to));
        }
    }
    for (const tinygltf::Node &n : g->nodes)
        d.nodes.push_back({n.name, n.skin, n.mesh, n.children, n.matrix, n.translation, n.rotation, n.scale});
    for (const tinygltf::Scene &sc : g->scenes) d.scenes.push_back({sc.nodes});
    d.defaultScene = g->defaultScene;
    for (const tinygltf::Animation &a : g->animations) {
        doc::Animation to;
        to.name = a.name;
        for (const tinygltf::AnimationChannel &ch : a.channels) to.channels.push_back({ch.sampler, ch.target_node, ch.target_path});
        for (const tinygltf::AnimationSampler &sa : a.samplers) to.samplers.push_back({sa.input, sa.output, sa.interpolation});
        d.animations.push_back(std::move(to));
    }
    for (const tinygltf::Skin &sk : g->skins) d.skins.push_back({sk.name, sk.joints, sk.skeleton, sk.inverseBindMatrices});
    materials_from_tinygltf(g, &d);
    *out = std::move(d);
}

// ---- accessors ----

int component_size(int type)
{
    switch (type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return 1;
    case TINYGLTF_COMPONENT_TYPE_SHORT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return 2;
    case TINYGLTF_COMPONENT_TYPE_INT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
    case TINYGLTF_COMPONENT_TYPE_FLOAT: return 4;
    default: return 0;
    }
}

int type_components(int type)
{
    switch (type) {
    case TINYGLTF_TYPE_SCALAR: return 1;
    case TINYGLTF_TYPE_VEC2: return 2;
    case TINYGLTF_TYPE_VEC3: return 3;
    case TINYGLTF_TYPE_VEC4: return 4;
    case TINYGLTF_TYPE_MAT4: return 16;
    default: return 0;
    }
}

double read_component(const unsigned char *p, int type, bool normalized)
{
    switch (type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE: {
        int8_t v;
        std::memcpy(&v, p, 1);
        return normalized ? std::fmax(v / 127.0, -1.0) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return normalized ? p[0] / 255.0 : p[0];
    case TINYGLTF_COMPONENT_TYPE_SHORT: {
        int16_t v;
        std::memcpy(&v, p, 2);
        return normalized ? std::fmax(v / 32767.0, -1.0) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
        uint16_t v;
        std::memcpy(&v, p, 2);
        return normalized ? v / 65535.0 : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
        uint32_t v;
        std::memcpy(&v, p, 4);
        return v;
    }
    case TINYGLTF_COMPONENT_TYPE_INT: {
        int32_t v;
        std::memcpy(&v, p, 4);
        return v;
    }
    default: {
        float v;
        std::memcpy(&v, p, 4);
        return v;
    }
    }
}

// A view of `count` elements of `elem_size` bytes `stride` apart, checked against its buffer.
template <class What>
bool view_span(const Context &c, int view_index, size_t offset, size_t count, size_t elem_size, size_t stride,
               const What &what, const unsigned char **out)
{
    const doc::Document &g = *c.doc;
    if (view_index < 0 || view_index >= (int)g.bufferViews.size()) {
        cb_fail(c.err, CB_ERR_INPUT, "%s: %s uses bufferView %d, which does not exist", c.name, what().c_str(), view_index);
        return false;
    }
    const doc::BufferView &view = g.bufferViews[(size_t)view_index];
    if (view.buffer < 0 || view.buffer >= (int)c.buffers.size()) {
        cb_fail(c.err, CB_ERR_INPUT, "%s: bufferView %d uses buffer %d, which does not exist", c.name, view_index, view.buffer);
        return false;
    }
    const Span &buf = c.buffers[(size_t)view.buffer];
    if (view.byteOffset > buf.size || view.byteLength > buf.size - view.byteOffset) {
        cb_fail(c.err, CB_ERR_INPUT, "%s: bufferView %d spans bytes %zu..%zu, past the end of buffer %d (%zu bytes)", c.name,
                view_index, view.byteOffset, view.byteOffset + view.byteLength, view.buffer, buf.size);
        return false;
    }
    // (count - 1) * stride + elem_size bytes from offset must fit in the view.
    if (count > 0) {
        unsigned long long need = (unsigned long long)(count - 1) * stride + elem_size;
        if (offset > view.byteLength || need > view.byteLength - offset) {
            cb_fail(c.err, CB_ERR_INPUT, "%s: %s reads %llu bytes from byte %zu of bufferView %d, which has %zu", c.name, what().c_str(),
                    need, offset, view_index, view.byteLength);
            return false;
        }
    }
    *out = buf.data + view.byteOffset + offset;
    return true;
}

// Reads an accessor into an array of `comps` values per element, applying normalization and
// sparse substitution. Tightly packed, aligned floats are used where they lie in the file's
// buffers (which the model owns); anything else is converted into the model's arena. what()
// names the accessor's use in messages: it is only formatted for one (a big rig has thousands
// of channels, and their names cost more than reading them in place).
template <typename T, class What>
bool read_accessor(const Context &c, int index, int want_comps, const What &what, T **out, size_t *count_out)
{
    const doc::Document &g = *c.doc;
    if (index < 0 || index >= (int)g.accessors.size()) {
        cb_fail(c.err, CB_ERR_INPUT, "%s: %s uses accessor %d, which does not exist", c.name, what().c_str(), index);
        return false;
    }
    const doc::Accessor &a = g.accessors[(size_t)index];
    int comps = type_components(a.type), csize = component_size(a.componentType);
    if (comps != want_comps || csize == 0) {
        cb_fail(c.err, CB_ERR_INPUT, "%s: %s: accessor %d has %d components of type %d, expected %d", c.name, what().c_str(), index,
                comps, a.componentType, want_comps);
        return false;
    }
    if (a.count > c.limits.max_accessor_count) {
        cb_fail_setting(c.err, CB_ERR_INPUT, CB_SETTING_MAX_ACCESSOR_COUNT,
                        "%s: %s: accessor %d claims %zu elements, over the limit of %llu", c.name, what().c_str(), index,
                        a.count, (unsigned long long)c.limits.max_accessor_count);
        return false;
    }
    size_t elem = (size_t)comps * csize;
    const unsigned char *p = nullptr;
    size_t stride = elem;
    if (a.bufferView >= 0 && a.count > 0) {
        // Bounds first, so a bogus count never drives an allocation.
        if ((size_t)a.bufferView < g.bufferViews.size() && g.bufferViews[(size_t)a.bufferView].byteStride)
            stride = g.bufferViews[(size_t)a.bufferView].byteStride;
        if (stride < elem) {
            cb_fail(c.err, CB_ERR_INPUT, "%s: %s: bufferView %d has byteStride %zu, smaller than its %zu-byte elements", c.name,
                    what().c_str(), a.bufferView, stride, elem);
            return false;
        }
        if (!view_span(c, a.bufferView, a.byteOffset, a.count, elem, stride, what, &p)) return false;
    }
    bool packed_floats = p && std::is_same<T, float>::value && a.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT &&
                         stride == elem && !a.sparse.isSparse;
    if (packed_floats && reinterpret_cast<uintptr_t>(p) % alignof(T) == 0) {
        // The model owns the buffer, and never writes into it (cb_model_validate normalizes
        // rotation keys in a copy): channels and accessors may share bytes.
        *out = reinterpret_cast<T *>(const_cast<unsigned char *>(p));
        *count_out = a.count;
        return true;
    }
    T *dst = static_cast<T *>(cb_model_alloc(c.model, a.count * (size_t)comps, sizeof(T))); /* zeroed */
    if (!dst) {
        cb_fail(c.err, CB_ERR_INTERNAL, "%s: out of memory reading %s", c.name, what().c_str());
        return false;
    }
    if (p && std::is_same<T, float>::value && a.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT && stride == elem) {
        std::memcpy(dst, p, a.count * elem);
    } else if (p) {
        for (size_t i = 0; i < a.count; ++i)
            for (int k = 0; k < comps; ++k) dst[i * comps + k] = (T)read_component(p + i * stride + k * csize, a.componentType, a.normalized);
    }
    if (a.sparse.isSparse && a.sparse.count > 0) {
        size_t n = (size_t)a.sparse.count;
        int isize = component_size(a.sparse.indices.componentType);
        const unsigned char *ip, *vp;
        if (n > a.count || isize == 0 || a.sparse.indices.byteOffset < 0 || a.sparse.values.byteOffset < 0 ||
            !view_span(c, a.sparse.indices.bufferView, (size_t)a.sparse.indices.byteOffset, n, isize, isize, what, &ip) ||
            !view_span(c, a.sparse.values.bufferView, (size_t)a.sparse.values.byteOffset, n, elem, elem, what, &vp)) {
            cb_fail(c.err, CB_ERR_INPUT, "%s: %s: accessor %d has an invalid sparse block", c.name, what().c_str(), index);
            return false;
        }
        for (size_t i = 0; i < n; ++i) {
            double target = read_component(ip + i * isize, a.sparse.indices.componentType, false);
            if (target < 0 || target >= (double)a.count) {
                cb_fail(c.err, CB_ERR_INPUT, "%s: %s: accessor %d sparse index %.0f is past its %zu elements", c.name, what().c_str(),
                        index, target, a.count);
                return false;
            }
            for (int k = 0; k < comps; ++k)
                dst[(size_t)target * comps + k] = (T)read_component(vp + i * elem + k * csize, a.componentType, a.normalized);
        }
    }
    *out = dst;
    *count_out = a.count;
    return true;
}

// ---- conversion to the core's structs ----

const char *name_or(cb_model *m, const std::string &name, const char *prefix, size_t index)
{
    if (!name.empty()) return cb_model_strdup(m, name.c_str());
    char buf[64];
    std::snprintf(buf, sizeof buf, "%s_%zu", prefix, index);
    return cb_model_strdup(m, buf);
}

bool convert_nodes(Context &c)
{
    const auto &nodes = c.doc->nodes;
    cb_model *m = c.model;
    m->node_count = (uint32_t)nodes.size();
    m->nodes = static_cast<cb_node *>(cb_model_alloc(m, nodes.size(), sizeof(cb_node)));
    for (size_t i = 0; i < nodes.size(); ++i) m->nodes[i].parent = -1;
    for (size_t i = 0; i < nodes.size(); ++i) {
        const doc::Node &src = nodes[i];
        cb_node *n = &m->nodes[i];
        n->name = name_or(m, src.name, "node", i);
        for (int child : src.children) {
            if (child < 0 || child >= (int)nodes.size()) {
                cb_fail(c.err, CB_ERR_INPUT, "%s: node %zu (%s) lists child %d, which does not exist", c.name, i, n->name, child);
                return false;
            }
            if (m->nodes[child].parent != -1 || (size_t)child == i) {
                cb_fail(c.err, CB_ERR_INPUT, "%s: node %d has two parents (%d and %zu); glTF nodes form a tree", c.name, child,
                        m->nodes[child].parent, i);
                return false;
            }
            m->nodes[child].parent = (int32_t)i;
        }
        n->rotation[3] = 1;
        n->scale[0] = n->scale[1] = n->scale[2] = 1;
        if (src.matrix.size() == 16) {
            n->has_matrix = true;
            for (int k = 0; k < 16; ++k) n->matrix[k] = src.matrix[k];
            continue; // the core derives TRS from the matrix
        }
        if (src.translation.size() == 3)
            for (int k = 0; k < 3; ++k) n->translation[k] = src.translation[k];
        if (src.scale.size() == 3)
            for (int k = 0; k < 3; ++k) n->scale[k] = src.scale[k];
        if (src.rotation.size() == 4)
            for (int k = 0; k < 4; ++k) n->rotation[k] = src.rotation[k]; // normalized by the core
    }
    return true;
}

// glTF wants every joint in the scene that is rendered; a joint elsewhere would be animated
// in a hierarchy the runtime never sees.
bool check_joints_in_scene(Context &c)
{
    const doc::Document &g = *c.doc;
    if (g.scenes.empty()) return true;
    int scene = g.defaultScene >= 0 && g.defaultScene < (int)g.scenes.size() ? g.defaultScene : 0;
    const std::vector<int> &roots = g.scenes[(size_t)scene].nodes;
    for (uint32_t s = 0; s < c.model->skin_count; ++s) {
        const cb_skin *skin = &c.model->skins[s];
        for (uint32_t j = 0; j < skin->joint_count; ++j) {
            int32_t n = skin->joints[j];
            if (n < 0 || n >= (int32_t)c.model->node_count) continue; // reported by validation
            uint32_t steps = 0;
            while (c.model->nodes[n].parent >= 0 && steps++ < c.model->node_count) n = c.model->nodes[n].parent;
            if (std::find(roots.begin(), roots.end(), n) == roots.end()) {
                cb_fail(c.err, CB_ERR_INPUT, "%s: skin %u joint %u (%s) is not in scene %d: its root node %d (%s) is not one "
                        "of the scene's nodes; add it to the scene", c.name, s, j, c.model->nodes[skin->joints[j]].name,
                        scene, n, c.model->nodes[n].name);
                return false;
            }
        }
    }
    return true;
}

bool convert_skins(Context &c)
{
    const auto &skins = c.doc->skins;
    cb_model *m = c.model;
    m->skin_count = (uint32_t)skins.size();
    m->skins = static_cast<cb_skin *>(cb_model_alloc(m, skins.size(), sizeof(cb_skin)));
    for (size_t s = 0; s < skins.size(); ++s) {
        const doc::Skin &src = skins[s];
        cb_skin *skin = &m->skins[s];
        skin->name = name_or(m, src.name, "skin", s);
        skin->skeleton = src.skeleton;
        if (src.joints.size() > c.limits.max_joints) {
            cb_fail_setting(c.err, CB_ERR_INPUT, CB_SETTING_MAX_JOINTS, "%s: skin %zu (%s) has %zu joints, over the limit of %u",
                            c.name, s, skin->name, src.joints.size(), c.limits.max_joints);
            return false;
        }
        skin->joint_count = (uint32_t)src.joints.size();
        skin->joints = static_cast<int32_t *>(cb_model_alloc(m, src.joints.size(), sizeof(int32_t)));
        skin->inverse_bind = static_cast<double *>(cb_model_alloc(m, src.joints.size() * 16, sizeof(double)));
        if (!skin->joints || !skin->inverse_bind) return false;
        for (size_t j = 0; j < src.joints.size(); ++j) {
            skin->joints[j] = src.joints[j];
            for (int k = 0; k < 16; ++k) skin->inverse_bind[j * 16 + k] = k % 5 == 0 ? 1.0 : 0.0; // identity
        }
        if (src.inverseBindMatrices >= 0) {
            double *ibm;
            size_t count;
            auto what = [s] { return "skin " + std::to_string(s) + " inverseBindMatrices"; };
            if (!read_accessor(c, src.inverseBindMatrices, 16, what, &ibm, &count)) return false;
            if (count < src.joints.size()) {
                cb_fail(c.err, CB_ERR_INPUT, "%s: skin %zu (%s) has %zu inverse bind matrices for %zu joints", c.name, s,
                        skin->name, count, src.joints.size());
                return false;
            }
            std::memcpy(skin->inverse_bind, ibm, src.joints.size() * 16 * sizeof(double));
        }
    }
    return true;
}

bool convert_primitive(Context &c, size_t node_index, const doc::Primitive &p, std::vector<cb_primitive> *out)
{
    const int *pos = p.attribute("POSITION"), *jnt = p.attribute("JOINTS_0"), *wgt = p.attribute("WEIGHTS_0");
    if (!pos || !jnt || !wgt) return true; // not skinned
    const doc::Node &node = c.doc->nodes[node_index];
    auto where = [&] { return "mesh node " + std::to_string(node_index) + " (" + node.name + ")"; };
    float *positions, *weights, *normals;
    double *joints = nullptr;
    uint16_t *joints16 = nullptr;
    uint32_t *indices;
    size_t n, nj, nw, nn, ni;
    // Joint indices of 8 or 16 bits (all glTF allows) are read as they are; any other type is
    // read as numbers and checked against 0..65535 below.
    const auto &acc = c.doc->accessors;
    int jt = *jnt >= 0 && (size_t)*jnt < acc.size() && !acc[(size_t)*jnt].normalized ? acc[(size_t)*jnt].componentType : 0;
    bool small = jt == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE || jt == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT;
    auto jwhat = [&] { return where() + " JOINTS_0"; };
    if (!read_accessor(c, *pos, 3, [&] { return where() + " POSITION"; }, &positions, &n) ||
        !(small ? read_accessor(c, *jnt, 4, jwhat, &joints16, &nj) : read_accessor(c, *jnt, 4, jwhat, &joints, &nj)) ||
        !read_accessor(c, *wgt, 4, [&] { return where() + " WEIGHTS_0"; }, &weights, &nw))
        return false;
    if (nj != n || nw != n) {
        cb_fail(c.err, CB_ERR_INPUT, "%s: %s has %zu positions but %zu joints and %zu weights", c.name, where().c_str(), n, nj, nw);
        return false;
    }
    if (!joints16 && !(joints16 = static_cast<uint16_t *>(cb_model_alloc(c.model, n * 4, sizeof(uint16_t))))) return false;
    for (size_t i = 0; joints && i < n * 4; ++i) {
        if (joints[i] < 0 || joints[i] > 65535) {
            cb_fail(c.err, CB_ERR_INPUT, "%s: %s has joint index %.0f outside 0..65535", c.name, where().c_str(), joints[i]);
            return false;
        }
        joints16[i] = (uint16_t)joints[i];
    }
    cb_primitive prim{};
    prim.node = (int32_t)node_index;
    prim.skin = node.skin;
    prim.vertex_count = (uint32_t)n;
    if (const int *nrm = p.attribute("NORMAL")) {
        if (!read_accessor(c, *nrm, 3, [&] { return where() + " NORMAL"; }, &normals, &nn)) return false;
        if (nn == n) prim.normals = normals;
    }
    if (const int *uv = p.attribute("TEXCOORD_0")) { /* only `mesh` carries it: a broken one is left out, never an error */
        float *texcoords;
        size_t nt;
        cb_error uv_err{};
        Context quiet = c;
        quiet.err = &uv_err;
        if (read_accessor(quiet, *uv, 2, [&] { return where() + " TEXCOORD_0"; }, &texcoords, &nt) && nt == n)
            prim.texcoords = texcoords;
    }
    if (p.material >= 0 && (uint32_t)p.material < c.model->material_count) prim.material = &c.model->materials[p.material];
    prim.colors = read_colors(c, p, n);
    if (p.indices >= 0) {
        if (!read_accessor(c, p.indices, 1, [&] { return where() + " indices"; }, &indices, &ni)) return false;
        prim.index_count = (uint32_t)ni;
        prim.indices = indices;
    }
    for (auto &a : p.attributes) { /* every attribute, as the file types it: what a runtime uploads */
        const doc::Accessor &acc = c.doc->accessors[(size_t)a.second];
        uint32_t elem = (uint32_t)(type_components(acc.type) * component_size(acc.componentType));
        prim.vertex_bytes += (elem + 3) / 4 * 4;
    }
    if (p.indices >= 0) prim.index_bytes = component_size(c.doc->accessors[(size_t)p.indices].componentType) == 4 ? 4 : 2;
    prim.positions = positions;
    prim.joints = joints16;
    prim.weights = weights;
    out->push_back(prim);
    return true;
}

float *read_colors(Context &c, const doc::Primitive &p, size_t vertex_count)
{
    const int *color = p.attribute("COLOR_0");
    if (!color || *color < 0 || (size_t)*color >= c.doc->accessors.size()) return nullptr;
    int comps = type_components(c.doc->accessors[(size_t)*color].type);
    if (comps != 3 && comps != 4) return nullptr;
    float *read, *rgba;
    size_t n;
    cb_error quiet_err{}; /* only `mesh` carries it: a broken one is left out, never an error */
    Context quiet = c;
    quiet.err = &quiet_err;
    if (!read_accessor(quiet, *color, comps, [] { return std::string("COLOR_0"); }, &read, &n) || n != vertex_count) return nullptr;
    if (comps == 4) return read;
    if (!(rgba = static_cast<float *>(cb_model_alloc(c.model, n * 4, sizeof(float))))) return nullptr;
    for (size_t v = 0; v < n; ++v) {
        std::memcpy(rgba + v * 4, read + v * 3, 3 * sizeof(float));
        rgba[v * 4 + 3] = 1;
    }
    return rgba;
}

bool convert_meshes(Context &c)
{
    const doc::Document &g = *c.doc;
    std::vector<cb_primitive> prims;
    for (size_t i = 0; i < g.nodes.size(); ++i) {
        const doc::Node &node = g.nodes[i];
        if (node.mesh < 0 || node.skin < 0) continue;
        if (node.mesh >= (int)g.meshes.size() || node.skin >= (int)g.skins.size()) {
            cb_fail(c.err, CB_ERR_INPUT, "%s: node %zu uses mesh %d / skin %d, which do not exist", c.name, i, node.mesh, node.skin);
            return false;
        }
        for (const doc::Primitive &p : g.meshes[(size_t)node.mesh].primitives)
            if (!convert_primitive(c, i, p, &prims)) return false;
    }
    cb_model *m = c.model;
    m->primitive_count = (uint32_t)prims.size();
    m->primitives = static_cast<cb_primitive *>(cb_model_alloc(m, prims.size(), sizeof(cb_primitive)));
    std::copy(prims.begin(), prims.end(), m->primitives);
    return true;
}

bool parse_interpolation(const std::string &s, cb_interp *out)
{
    if (s.empty() || s == "LINEAR") *out = CB_INTERP_LINEAR;
    else if (s == "STEP") *out = CB_INTERP_STEP;
    else if (s == "CUBICSPLINE") *out = CB_INTERP_CUBICSPLINE;
    else return false;
    return true;
}

bool convert_channel(Context &c, size_t a, size_t ci, const doc::Animation &src, std::vector<cb_channel> *out)
{
    const doc::AnimationChannel &ch = src.channels[ci];
    const std::string &path = ch.target_path;
    auto where = [&] { return "clip '" + std::string(c.model->animations[a].name) + "' channel " + std::to_string(ci); };
    if (path == "weights") {
        c.model->ignored_morph_channels++;
        return true;
    }
    cb_channel dst{};
    if (path == "translation") dst.path = CB_PATH_TRANSLATION;
    else if (path == "rotation") dst.path = CB_PATH_ROTATION;
    else if (path == "scale") dst.path = CB_PATH_SCALE;
    else {
        cb_fail(c.err, CB_ERR_INPUT, "%s: %s animates '%s'; glTF 2.0 allows translation, rotation, scale and weights", c.name,
                where().c_str(), path.c_str());
        return false;
    }
    if (ch.target_node < 0) return true; // targets something else (an extension); not a joint
    if (ch.sampler < 0 || ch.sampler >= (int)src.samplers.size()) {
        cb_fail(c.err, CB_ERR_INPUT, "%s: %s uses sampler %d, which does not exist", c.name, where().c_str(), ch.sampler);
        return false;
    }
    const doc::AnimationSampler &s = src.samplers[(size_t)ch.sampler];
    if (!parse_interpolation(s.interpolation, &dst.interp)) {
        cb_fail(c.err, CB_ERR_INPUT, "%s: %s has interpolation '%s'; use LINEAR, STEP or CUBICSPLINE", c.name, where().c_str(),
                s.interpolation.c_str());
        return false;
    }
    dst.node = ch.target_node;
    int comps = dst.path == CB_PATH_ROTATION ? 4 : 3;
    float *times, *values;
    size_t nt, nv;
    if (!read_accessor(c, s.input, 1, [&] { return where() + " key times"; }, &times, &nt) ||
        !read_accessor(c, s.output, comps, [&] { return where() + " values"; }, &values, &nv))
        return false;
    size_t per_key = dst.interp == CB_INTERP_CUBICSPLINE ? 3 : 1;
    if (nv != nt * per_key) {
        cb_fail(c.err, CB_ERR_INPUT, "%s: %s has %zu key times but %zu values (expected %zu)", c.name, where().c_str(), nt, nv,
                nt * per_key);
        return false;
    }
    dst.key_count = (uint32_t)nt;
    dst.times = times;
    dst.values = values;
    out->push_back(dst);
    return true;
}

bool convert_animations(Context &c)
{
    const auto &anims = c.doc->animations;
    cb_model *m = c.model;
    m->animation_count = (uint32_t)anims.size();
    m->animations = static_cast<cb_animation *>(cb_model_alloc(m, anims.size(), sizeof(cb_animation)));
    for (size_t a = 0; a < anims.size(); ++a) {
        cb_animation *dst = &m->animations[a];
        dst->name = name_or(m, anims[a].name, "animation", a);
        std::vector<cb_channel> channels;
        for (size_t ci = 0; ci < anims[a].channels.size(); ++ci)
            if (!convert_channel(c, a, ci, anims[a], &channels)) return false;
        dst->channel_count = (uint32_t)channels.size();
        dst->channels = static_cast<cb_channel *>(cb_model_alloc(m, channels.size(), sizeof(cb_channel)));
        std::copy(channels.begin(), channels.end(), dst->channels);
    }
    return true;
}

// ---- buffers: owned by the model, read in place ----

// The bytes an accessor reads (its sparse blocks included), for finding overlaps.

} // namespace cbgltf
