/* pf_gltf: the tinygltf shim (see pf_gltf.h). The only C++ in softgi.
 *
 * tinygltf parses JSON/GLB and decodes images; everything it hands back is
 * treated as untrusted: every accessor, bufferView, buffer, index and object
 * reference is range-checked here before a byte is read, because tinygltf
 * 2.7 checks few of them. The result is flattened into pf_scene (plain C).
 *
 * Order of work: pick the scene, walk its node forest (explicit stack, cycle
 * and depth checks), and for every mesh primitive read positions, normals,
 * uvs and indices, expand strips/fans to lists, transform to world space,
 * fix winding under mirroring transforms, drop zero-area triangles, generate
 * flat normals where NORMAL is missing. Then materials, the textures they
 * use (mips built here), cameras and KHR_lights_punctual lights. */
#include "pf_gltf.h"
#include "pf_anim.h"
#include "pf_budget.h"
#include "pf_decode.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>

#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <new>
#include <string>
#include <vector>

#include <cjson/cJSON.h>
#include <tiny_gltf.h>

namespace {

/* Limits that keep a hostile file from asking for absurd memory or time. */
const size_t kMaxAccessorCount = size_t(1) << 28;  /* elements per accessor */
const size_t kMaxSceneTriangles = size_t(1) << 25; /* after instancing */
/* Elements an accessor without a bufferView may claim (they are zeros, or
 * sparse substitutions): at most this many per byte of input, plus a floor.
 * Without it a 200-byte file can ask for gigabytes of zeros. */
const size_t kImplicitPerByte = 64;
const size_t kImplicitFloor = size_t(1) << 20;
const int kMaxNodeDepth = 256;
const size_t kMaxFileBytes = size_t(1) << 32;

struct LoadError {
    pf_result code;
    std::string message;
};

[[noreturn]] void fail(pf_result code, const std::string &msg) { throw LoadError{code, msg}; }

std::string fmt(const char *f, ...) __attribute__((format(printf, 1, 2)));
std::string fmt(const char *f, ...)
{
    char buf[512];
    va_list ap;
    va_start(ap, f);
    vsnprintf(buf, sizeof buf, f, ap);
    va_end(ap);
    return buf;
}

/* ---------------------------------------------------------------- checks before tinygltf
 * tinygltf 2.7 accepts several things silently that a careful loader must
 * not: it converts extras and extensions recursively (a 30 KB file nested
 * 15,000 deep overflows the stack), drops a baseColorFactor of the wrong
 * length, reads "indices": -3 as "not indexed", and loads glTF 1.0 and GLB
 * version 1 headers as if they were 2.0. These checks run on the raw JSON
 * first: a non-recursive nesting scan, the GLB header, then a cJSON pass
 * (cJSON bounds its own nesting at 1000; ours is far lower) over the fields
 * tinygltf would lose. */

const int kMaxJsonDepth = 64;

/* Deepest nesting of [ and { outside strings; no recursion. */
int json_depth(const char *p, size_t n)
{
    int depth = 0, deepest = 0;
    bool in_string = false;
    for (size_t i = 0; i < n; i++) {
        char c = p[i];
        if (in_string) {
            if (c == '\\') i++;
            else if (c == '"') in_string = false;
        } else if (c == '"') in_string = true;
        else if (c == '[' || c == '{') deepest = ++depth > deepest ? depth : deepest;
        else if ((c == ']' || c == '}') && depth > 0) depth--;
    }
    return deepest;
}

/* The JSON text of a .gltf or of a GLB's first chunk (glTF 2.0 spec,
 * Sec. 4.4 "Binary glTF Layout"). */
void json_of(const unsigned char *data, size_t size, bool is_glb, const char **json, size_t *json_size)
{
    if (!is_glb) {
        *json = reinterpret_cast<const char *>(data);
        *json_size = size;
        return;
    }
    uint32_t version, chunk_len, chunk_type;
    if (size < 20) fail(PF_ERR_PARSE, "binary glTF: the file is shorter than its 20-byte header");
    memcpy(&version, data + 4, 4);
    memcpy(&chunk_len, data + 12, 4);
    memcpy(&chunk_type, data + 16, 4);
    if (version != 2)
        fail(PF_ERR_UNSUPPORTED, fmt("binary glTF version %u (softgi reads glTF 2.0, version 2)", version));
    if (chunk_type != 0x4E4F534Au) fail(PF_ERR_PARSE, "binary glTF: the first chunk is not JSON");
    if (chunk_len > size - 20) fail(PF_ERR_PARSE, "binary glTF: the JSON chunk runs past the end of the file");
    *json = reinterpret_cast<const char *>(data + 20);
    *json_size = chunk_len;
}

/* A glTF object reference or count: a non-negative integer. */
void check_index(const cJSON *v, const std::string &where)
{
    if (!cJSON_IsNumber(v) || !(v->valuedouble >= 0.0) || v->valuedouble != std::floor(v->valuedouble) ||
        v->valuedouble > 2147483647.0)
        fail(PF_ERR_INDEX_RANGE, cJSON_IsNumber(v) ? fmt("%s is %g; it must be a non-negative integer index",
                                                         where.c_str(), v->valuedouble)
                                                   : fmt("%s must be a non-negative integer index", where.c_str()));
}

void check_number_array(const cJSON *v, int n, const std::string &where)
{
    if (!v) return;
    if (!cJSON_IsArray(v) || cJSON_GetArraySize(v) != n)
        fail(PF_ERR_PARSE, fmt("%s must be an array of %d numbers", where.c_str(), n));
    for (const cJSON *e = v->child; e; e = e->next)
        if (!cJSON_IsNumber(e)) fail(PF_ERR_PARSE, fmt("%s must be an array of %d numbers", where.c_str(), n));
}

/* Every object reference the glTF 2.0 schema defines, by property name. A
 * property inside "extras" is application data and is not looked at. */
bool is_reference_key(const char *k)
{
    static const char *const keys[] = {"indices", "material", "mesh",  "camera", "skin",  "source",
                                       "sampler", "bufferView", "buffer", "index", "scene", "node",
                                       "light", "input",   "output", "texCoord", "skeleton"};
    for (const char *r : keys)
        if (strcmp(k, r) == 0) return true;
    return false;
}
bool is_reference_list_key(const char *k)
{
    return strcmp(k, "children") == 0 || strcmp(k, "nodes") == 0 || strcmp(k, "joints") == 0;
}

void check_references(const cJSON *obj, const std::string &where, int depth)
{
    if (depth > kMaxJsonDepth) return; /* unreachable: json_depth ran first */
    for (const cJSON *c = obj->child; c; c = c->next) {
        const char *k = c->string;
        std::string at = k ? where + "." + k : where;
        if (k && strcmp(k, "extras") == 0) continue;
        if (k && strcmp(k, "extensions") == 0 && cJSON_IsObject(c)) {
            /* only the extensions softgi reads; others are the extension's own business */
            const cJSON *lp = cJSON_GetObjectItemCaseSensitive(c, "KHR_lights_punctual");
            if (cJSON_IsObject(lp)) check_references(lp, at + ".KHR_lights_punctual", depth + 1);
            continue;
        }
        if (k && cJSON_IsNumber(c) && is_reference_key(k)) check_index(c, at);
        else if (k && depth > 0 && is_reference_list_key(k) && cJSON_IsArray(c)) {
            int i = 0;
            for (const cJSON *e = c->child; e; e = e->next, i++) check_index(e, fmt("%s[%d]", at.c_str(), i));
        } else if (k && (strcmp(k, "attributes") == 0) && cJSON_IsObject(c)) {
            for (const cJSON *e = c->child; e; e = e->next) check_index(e, at + "." + e->string);
        } else if (k && strcmp(k, "targets") == 0 && cJSON_IsArray(c)) { /* morph targets: attribute -> accessor */
            int i = 0;
            for (const cJSON *t = c->child; t; t = t->next, i++)
                if (cJSON_IsObject(t))
                    for (const cJSON *e = t->child; e; e = e->next)
                        check_index(e, fmt("%s[%d].%s", at.c_str(), i, e->string));
        } else if (cJSON_IsArray(c)) {
            int i = 0;
            for (const cJSON *e = c->child; e; e = e->next, i++)
                if (cJSON_IsObject(e) || cJSON_IsArray(e)) check_references(e, fmt("%s[%d]", at.c_str(), i), depth + 1);
        } else if (cJSON_IsObject(c))
            check_references(c, at, depth + 1);
    }
}

void check_json(const char *json, size_t n)
{
    int depth = json_depth(json, n);
    if (depth > kMaxJsonDepth)
        fail(PF_ERR_PARSE, fmt("the JSON is nested %d levels deep; softgi allows %d", depth, kMaxJsonDepth));
    const char *end = nullptr;
    cJSON *root = cJSON_ParseWithLengthOpts(json, n, &end, 0);
    if (!root)
        fail(PF_ERR_PARSE, fmt("not a loadable glTF 2.0 file: invalid JSON at byte %zu",
                               end && end >= json ? size_t(end - json) : size_t(0)));
    struct Free {
        cJSON *r;
        ~Free() { cJSON_Delete(r); }
    } guard{root};
    if (!cJSON_IsObject(root)) fail(PF_ERR_PARSE, "the JSON is not an object");
    const cJSON *asset = cJSON_GetObjectItemCaseSensitive(root, "asset");
    const cJSON *version = asset ? cJSON_GetObjectItemCaseSensitive(asset, "version") : nullptr;
    if (!cJSON_IsString(version))
        fail(PF_ERR_PARSE, "asset.version is missing (glTF 2.0 requires it)");
    if (strncmp(version->valuestring, "2.", 2) != 0)
        fail(PF_ERR_UNSUPPORTED, fmt("glTF version '%.20s' (softgi reads glTF 2.0)", version->valuestring));
    const cJSON *minv = cJSON_GetObjectItemCaseSensitive(asset, "minVersion");
    if (cJSON_IsString(minv) && strcmp(minv->valuestring, "2.0") != 0)
        fail(PF_ERR_UNSUPPORTED, fmt("the file needs glTF %.20s (softgi reads glTF 2.0)", minv->valuestring));
    const cJSON *mats = cJSON_GetObjectItemCaseSensitive(root, "materials");
    if (cJSON_IsArray(mats)) {
        int i = 0;
        for (const cJSON *m = mats->child; m; m = m->next, i++) {
            const cJSON *pbr = cJSON_GetObjectItemCaseSensitive(m, "pbrMetallicRoughness");
            if (pbr)
                check_number_array(cJSON_GetObjectItemCaseSensitive(pbr, "baseColorFactor"), 4,
                                   fmt("material %d: baseColorFactor", i));
            check_number_array(cJSON_GetObjectItemCaseSensitive(m, "emissiveFactor"), 3,
                               fmt("material %d: emissiveFactor", i));
        }
    }
    check_references(root, "glTF", 0);
}

/* ---------------------------------------------------------------- file system
 * Our own callbacks: tinygltf's default ExpandFilePath runs wordexp(), which
 * we do not want anywhere near file names from untrusted files.
 *
 * The trust boundary: a scene may read files in its own folder (and below)
 * and nothing else. tinygltf percent-decodes a uri ("%2e%2e/" is "../") and
 * joins it to the folder (and, second, to the working directory), so the
 * joined string proves nothing: "<dir>/../../etc/passwd" starts with
 * "<dir>/". Every candidate is therefore resolved with realpath() (which
 * removes "." and ".." and follows every symbolic link) and must lie strictly
 * inside the realpath of the scene's folder. A file outside it is treated
 * exactly like a missing one, so the messages reveal nothing about files
 * outside the folder. Only regular files are read (a FIFO would block, a
 * device would never end), and their size counts against the memory budget
 * before a byte is read. */
struct FsContext {
    std::string base_real; /* realpath of the scene's folder, with a trailing '/' */
    pf_budget *budget;     /* external files are read whole: they count */
};

/* The resolved path if `path` exists inside the scene's folder, else "". */
std::string fs_resolve_inside(const std::string &path, const FsContext *ctx)
{
    if (!ctx || ctx->base_real.empty()) return std::string();
    char *rp = realpath(path.c_str(), nullptr);
    if (!rp) return std::string();
    std::string r(rp);
    free(rp);
    if (r.size() <= ctx->base_real.size() || r.compare(0, ctx->base_real.size(), ctx->base_real) != 0)
        return std::string();
    return r;
}
bool fs_exists(const std::string &path, void *user)
{
    struct stat st;
    std::string r = fs_resolve_inside(path, static_cast<const FsContext *>(user));
    return !r.empty() && stat(r.c_str(), &st) == 0 && S_ISREG(st.st_mode);
}
std::string fs_expand(const std::string &path, void *) { return path; }
/* Reads a whole regular file. O_NONBLOCK: opening a FIFO must not wait for a
 * writer; fstat then refuses anything but a regular file. With a budget, the
 * size is taken from it before the buffer is allocated. */
bool read_file(std::vector<unsigned char> *out, std::string *err, const std::string &path, pf_budget *budget)
{
    int fd = open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) {
        if (err) *err += "cannot open '" + path + "'\n";
        return false;
    }
    struct stat st;
    bool ok = fstat(fd, &st) == 0 && S_ISREG(st.st_mode);
    if (!ok) {
        close(fd);
        if (err) *err += "'" + path + "' is not a regular file\n";
        return false;
    }
    size_t size = size_t(st.st_size);
    if (st.st_size < 0 || size > kMaxFileBytes) {
        close(fd);
        if (err) *err += "'" + path + "' is larger than 4 GiB\n";
        return false;
    }
    if (budget) {
        pf_error e;
        if (pf_budget_take(budget, size, ("file '" + path + "'").c_str(), &e) != PF_OK) {
            close(fd);
            if (err) *err += std::string(e.message) + "\n";
            return false;
        }
    }
    out->resize(size);
    size_t got = 0;
    while (got < size) {
        ssize_t n = read(fd, out->data() + got, size - got);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) break;
        got += size_t(n);
    }
    close(fd);
    if (got != size) {
        if (err) *err += "cannot read '" + path + "'\n";
        return false;
    }
    return true;
}
bool fs_read(std::vector<unsigned char> *out, std::string *err, const std::string &path, void *user)
{
    const FsContext *ctx = static_cast<const FsContext *>(user);
    std::string r = fs_resolve_inside(path, ctx);
    if (r.empty()) {
        if (err) *err += "file not found (or outside the scene's folder)\n";
        return false;
    }
    return read_file(out, err, r, ctx->budget);
}
bool fs_write(std::string *err, const std::string &, const std::vector<unsigned char> &, void *)
{
    if (err) *err += "softgi never writes glTF files\n";
    return false;
}

/* With ignore_textures, images are not kept at all. */
bool skip_image(tinygltf::Image *, const int, std::string *, std::string *, int, int, const unsigned char *, int,
                void *)
{
    return true;
}

/* tinygltf calls its image loader for every image while parsing. For
 * bufferView images the byte range it hands over is unchecked (tinygltf 2.7
 * does not check the view against its buffer: reading it would overrun), so
 * they are not touched here; decode_image validates the view first. For uri
 * and data-uri images the bytes come from a vector of the right size: they
 * are kept encoded, and only images a material uses are decoded. */
bool defer_image(tinygltf::Image *img, const int, std::string *, std::string *, int, int, const unsigned char *bytes,
                 int size, void *)
{
    if (img->bufferView >= 0) return true;
    if (bytes && size > 0) img->image.assign(bytes, bytes + size);
    img->width = img->height = img->component = img->bits = 0;
    return true;
}

/* ---------------------------------------------------------------- accessors */

size_t component_size(int type)
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
    case TINYGLTF_TYPE_MAT4: return 16; /* inverseBindMatrices; float only, so no column padding */
    default: return 0;
    }
}

/* Reads one component as float, applying the glTF normalisation rules. */
float read_component(const unsigned char *p, int type, bool normalized)
{
    switch (type) {
    case TINYGLTF_COMPONENT_TYPE_FLOAT: {
        float f;
        memcpy(&f, p, 4);
        return f;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return normalized ? float(p[0]) / 255.0f : float(p[0]);
    case TINYGLTF_COMPONENT_TYPE_BYTE: {
        float v = float(int8_t(p[0]));
        return normalized ? fmaxf(v / 127.0f, -1.0f) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
        uint16_t v;
        memcpy(&v, p, 2);
        return normalized ? float(v) / 65535.0f : float(v);
    }
    case TINYGLTF_COMPONENT_TYPE_SHORT: {
        int16_t v;
        memcpy(&v, p, 2);
        return normalized ? fmaxf(float(v) / 32767.0f, -1.0f) : float(v);
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
        uint32_t v;
        memcpy(&v, p, 4);
        return float(v);
    }
    default: return 0.0f;
    }
}

uint32_t read_index(const unsigned char *p, int type)
{
    switch (type) {
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return p[0];
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
        uint16_t v;
        memcpy(&v, p, 2);
        return v;
    }
    default: {
        uint32_t v;
        memcpy(&v, p, 4);
        return v;
    }
    }
}

/* A checked window onto bufferView bytes: base points at element 0. */
struct View {
    const unsigned char *base = nullptr;
    size_t stride = 0;
};

/* Checks that `count` elements of `elem` bytes at `offset` with `stride`
 * (0 = tight) fit inside bufferView `bv_index`, and returns the window. */
View checked_view(const tinygltf::Model &m, int bv_index, size_t offset, size_t count, size_t elem,
                  const std::string &what)
{
    if (bv_index < 0 || size_t(bv_index) >= m.bufferViews.size())
        fail(PF_ERR_INDEX_RANGE, fmt("%s refers to bufferView %d, but the file has %zu", what.c_str(), bv_index,
                                     m.bufferViews.size()));
    const tinygltf::BufferView &bv = m.bufferViews[size_t(bv_index)];
    if (bv.buffer < 0 || size_t(bv.buffer) >= m.buffers.size())
        fail(PF_ERR_INDEX_RANGE,
             fmt("bufferView %d refers to buffer %d, but the file has %zu", bv_index, bv.buffer, m.buffers.size()));
    const tinygltf::Buffer &buf = m.buffers[size_t(bv.buffer)];
    if (bv.byteOffset > buf.data.size() || bv.byteLength > buf.data.size() - bv.byteOffset)
        fail(PF_ERR_ACCESSOR, fmt("bufferView %d (offset %zu, length %zu) lies past the end of buffer %d (%zu bytes)",
                                  bv_index, bv.byteOffset, bv.byteLength, bv.buffer, buf.data.size()));
    size_t stride = bv.byteStride ? bv.byteStride : elem;
    if (stride < elem)
        fail(PF_ERR_ACCESSOR, fmt("%s: byteStride %zu of bufferView %d is smaller than its element (%zu bytes)",
                                  what.c_str(), stride, bv_index, elem));
    if (count > 0) {
        /* offset + stride*(count-1) + elem <= byteLength, without overflow
         * (count <= 2^28 and stride <= 2^8 by the checks above and tinygltf). */
        size_t need_hi = (count - 1) * stride;
        if (offset > bv.byteLength || elem > bv.byteLength - offset || need_hi > bv.byteLength - offset - elem)
            fail(PF_ERR_ACCESSOR, fmt("%s reads past the end of bufferView %d (needs %zu bytes, has %zu)",
                                      what.c_str(), bv_index, offset + need_hi + elem, bv.byteLength));
    }
    View v;
    v.base = buf.data.data() + bv.byteOffset + offset;
    v.stride = stride;
    return v;
}

const tinygltf::Accessor &get_accessor(const tinygltf::Model &m, int index, const std::string &what)
{
    if (index < 0 || size_t(index) >= m.accessors.size())
        fail(PF_ERR_INDEX_RANGE,
             fmt("%s refers to accessor %d, but the file has %zu", what.c_str(), index, m.accessors.size()));
    const tinygltf::Accessor &a = m.accessors[size_t(index)];
    if (a.count > kMaxAccessorCount)
        fail(PF_ERR_ACCESSOR, fmt("accessor %d has count %zu, more than softgi's limit of %zu", index, a.count,
                                  kMaxAccessorCount));
    return a;
}

/* Which component types an accessor may have where it is read. */
enum Components {
    kFloat,             /* float only (positions, normals, times, matrices) */
    kFloatOrNormalized, /* float or normalized (u)byte/(u)short (uvs, rotations, morph weights) */
    kFloatOrUnorm,      /* float or normalized unsigned byte/short (WEIGHTS_n) */
    kJointIndex         /* unsigned byte/short, not normalized (JOINTS_n), read as exact floats */
};

bool components_ok(const tinygltf::Accessor &a, Components c)
{
    const int t = a.componentType;
    const bool unorm = a.normalized && (t == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE ||
                                        t == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT);
    const bool snorm = a.normalized && (t == TINYGLTF_COMPONENT_TYPE_BYTE || t == TINYGLTF_COMPONENT_TYPE_SHORT);
    switch (c) {
    case kFloat: return t == TINYGLTF_COMPONENT_TYPE_FLOAT;
    case kFloatOrNormalized: return t == TINYGLTF_COMPONENT_TYPE_FLOAT || unorm || snorm;
    case kFloatOrUnorm: return t == TINYGLTF_COMPONENT_TYPE_FLOAT || unorm;
    case kJointIndex:
        return !a.normalized &&
               (t == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE || t == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT);
    }
    return false;
}

/* Reads a float-valued accessor (positions, normals, uvs) with `ncomp`
 * components, honouring byteStride, normalisation and sparse substitution. */
std::vector<float> read_floats(const tinygltf::Model &m, int index, int ncomp, Components comps,
                               size_t implicit_limit, const std::string &what)
{
    const tinygltf::Accessor &a = get_accessor(m, index, what);
    std::string where = fmt("accessor %d (%s)", index, what.c_str());
    if (a.bufferView < 0 && a.count > implicit_limit)
        fail(PF_ERR_ACCESSOR, fmt("%s has count %zu but no bufferView; softgi allows at most %zu such elements for "
                                  "a file of this size",
                                  where.c_str(), a.count, implicit_limit));
    if (type_components(a.type) != ncomp)
        fail(PF_ERR_ACCESSOR, fmt("%s must have %d components per element", where.c_str(), ncomp));
    size_t csize = component_size(a.componentType);
    bool ok_type = components_ok(a, comps);
    if (!ok_type || csize == 0)
        fail(PF_ERR_ACCESSOR, fmt("%s has component type %d, which is not allowed here", where.c_str(),
                                  a.componentType));
    size_t elem = csize * size_t(ncomp);
    std::vector<float> out(a.count * size_t(ncomp), 0.0f);
    if (a.bufferView >= 0) {
        View v = checked_view(m, a.bufferView, a.byteOffset, a.count, elem, where);
        for (size_t i = 0; i < a.count; i++)
            for (int c = 0; c < ncomp; c++)
                out[i * size_t(ncomp) + size_t(c)] =
                    read_component(v.base + i * v.stride + size_t(c) * csize, a.componentType, a.normalized);
    }
    if (a.sparse.isSparse) {
        if (a.sparse.count < 0 || size_t(a.sparse.count) > a.count)
            fail(PF_ERR_ACCESSOR, fmt("%s: sparse count %d exceeds the accessor count %zu", where.c_str(),
                                      a.sparse.count, a.count));
        size_t n = size_t(a.sparse.count);
        int itype = a.sparse.indices.componentType;
        size_t isize = component_size(itype);
        if (itype != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE && itype != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
            itype != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
            fail(PF_ERR_ACCESSOR, fmt("%s: sparse indices must be unsigned integers", where.c_str()));
        if (a.sparse.indices.byteOffset < 0 || a.sparse.values.byteOffset < 0)
            fail(PF_ERR_ACCESSOR, fmt("%s: negative sparse byteOffset", where.c_str()));
        View iv = checked_view(m, a.sparse.indices.bufferView, size_t(a.sparse.indices.byteOffset), n, isize,
                               where + " sparse indices");
        iv.stride = isize; /* sparse data is always tightly packed */
        View vv = checked_view(m, a.sparse.values.bufferView, size_t(a.sparse.values.byteOffset), n, elem,
                               where + " sparse values");
        vv.stride = elem;
        for (size_t i = 0; i < n; i++) {
            uint32_t target = read_index(iv.base + i * isize, itype);
            if (target >= a.count)
                fail(PF_ERR_INDEX_RANGE, fmt("%s: sparse index %u is past the accessor count %zu", where.c_str(),
                                             target, a.count));
            for (int c = 0; c < ncomp; c++)
                out[size_t(target) * size_t(ncomp) + size_t(c)] =
                    read_component(vv.base + i * elem + size_t(c) * csize, a.componentType, a.normalized);
        }
    }
    return out;
}

/* Reads an index accessor (u8/u16/u32 scalars). */
std::vector<uint32_t> read_indices(const tinygltf::Model &m, int index, const std::string &what)
{
    const tinygltf::Accessor &a = get_accessor(m, index, what);
    std::string where = fmt("accessor %d (%s)", index, what.c_str());
    if (a.type != TINYGLTF_TYPE_SCALAR)
        fail(PF_ERR_ACCESSOR, fmt("%s must be SCALAR", where.c_str()));
    if (a.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
        a.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
        a.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
        fail(PF_ERR_ACCESSOR, fmt("%s must be unsigned byte, short or int", where.c_str()));
    if (a.sparse.isSparse)
        fail(PF_ERR_UNSUPPORTED, fmt("%s: sparse index accessors are not supported", where.c_str()));
    if (a.bufferView < 0) fail(PF_ERR_ACCESSOR, fmt("%s has no bufferView", where.c_str()));
    size_t csize = component_size(a.componentType);
    View v = checked_view(m, a.bufferView, a.byteOffset, a.count, csize, where);
    std::vector<uint32_t> out(a.count);
    for (size_t i = 0; i < a.count; i++) out[i] = read_index(v.base + i * v.stride, a.componentType);
    return out;
}

/* ---------------------------------------------------------------- nodes */

/* Node `index`'s static transform (glTF 2.0 Sec. 3.5.3): its matrix, or
 * T R S with the quaternion normalised, checked finite. The TRS (or the
 * matrix) also goes into *rest, which posing starts from (pf_anim.h); both
 * build the matrix with pf_anim_trs_matrix, so they agree bit for bit. */
pf_mat4 node_local(const tinygltf::Node &n, int index, pf_anim_node *rest)
{
    pf_mat4 r = pf_mat4_identity();
    double t[3] = {0, 0, 0}, q[4] = {0, 0, 0, 1}, s[3] = {1, 1, 1};
    if (!n.matrix.empty()) {
        if (n.matrix.size() != 16) fail(PF_ERR_PARSE, fmt("node %d: matrix must have 16 numbers", index));
        for (int i = 0; i < 16; i++) r.m[i] = n.matrix[size_t(i)];
    } else {
        if (!n.translation.empty()) {
            if (n.translation.size() != 3) fail(PF_ERR_PARSE, fmt("node %d: translation must have 3 numbers", index));
            for (int i = 0; i < 3; i++) t[i] = n.translation[size_t(i)];
        }
        if (!n.rotation.empty()) {
            if (n.rotation.size() != 4) fail(PF_ERR_PARSE, fmt("node %d: rotation must have 4 numbers", index));
            for (int i = 0; i < 4; i++) q[i] = n.rotation[size_t(i)];
            double len = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
            if (!(len > 0.0) || !std::isfinite(len))
                fail(PF_ERR_NONFINITE, fmt("node %d: rotation quaternion is zero or non-finite", index));
            for (double &c : q) c /= len;
        }
        if (!n.scale.empty()) {
            if (n.scale.size() != 3) fail(PF_ERR_PARSE, fmt("node %d: scale must have 3 numbers", index));
            for (int i = 0; i < 3; i++) s[i] = n.scale[size_t(i)];
        }
        r = pf_anim_trs_matrix(t, q, s);
    }
    for (double v : r.m)
        if (!std::isfinite(v)) fail(PF_ERR_NONFINITE, fmt("node %d has a non-finite transform", index));
    if (rest) {
        rest->has_matrix = !n.matrix.empty();
        rest->matrix = r;
        memcpy(rest->t, t, sizeof t);
        memcpy(rest->r, q, sizeof q);
        memcpy(rest->s, s, sizeof s);
    }
    return r;
}

/* ---------------------------------------------------------------- animation
 * What posing needs (pf_anim.h): every node's static transform and the
 * walk order, the morph weights of the mesh nodes, the skins the scene
 * uses, the animations' channels and samplers, and per instanced primitive
 * its place in the scene and, when something deforms or moves it, its own
 * data. All of it read and checked here (glTF 2.0 Sec. 3.7.2.2, 3.7.3,
 * 3.11), everything kept counted against the memory budget. A channel that
 * animates a node outside the scene moves nothing and is not read. */

struct AnimReader {
    const tinygltf::Model &m;
    size_t implicit_limit;
    pf_budget *budget;
    bool keep;              /* the caller wants the pf_anim (pf_gltf_options.anim) */
    std::string *warnings;  /* the Builder's */
    pf_anim a;              /* owned until release() */
    std::vector<pf_anim_prim> prims;
    std::vector<char> trs_animated, weights_animated, moves, skin_moves;
    std::vector<int> sampler_use; /* per sampler of the clip being read: path and dim it was read for */

    AnimReader(const tinygltf::Model &model, size_t limit, pf_budget *b, bool k, std::string *w)
        : m(model), implicit_limit(limit), budget(b), keep(k), warnings(w)
    {
        memset(&a, 0, sizeof a);
        a.pose_clip = PF_ANIM_STATIC;
    }
    ~AnimReader()
    {
        for (pf_anim_prim &p : prims) pf_anim_prim_free(&p);
        pf_anim_free(&a);
    }
    AnimReader(const AnimReader &) = delete;
    AnimReader &operator=(const AnimReader &) = delete;

    void warn(const std::string &w)
    {
        if (warnings->size() < 900) *warnings += w + "\n";
    }

    /* Bytes for `what` from the budget, before they are allocated. */
    void take(uint64_t bytes, const std::string &what)
    {
        pf_error e;
        if (pf_budget_take(budget, bytes, what.c_str(), &e) != PF_OK) fail(e.code, e.message);
        a.memory_bytes += bytes;
    }

    template <typename T> static T *alloc(size_t n)
    {
        T *p = static_cast<T *>(calloc(n ? n : 1, sizeof(T)));
        if (!p) throw std::bad_alloc();
        return p;
    }

    /* ------------------------------------------------ nodes and morph weights */

    /* Morph targets of mesh `mi`: the same number in every primitive. */
    uint32_t mesh_targets(int mi)
    {
        const tinygltf::Mesh &mesh = m.meshes[size_t(mi)];
        size_t n = mesh.primitives.empty() ? 0 : mesh.primitives[0].targets.size();
        for (size_t p = 1; p < mesh.primitives.size(); p++)
            if (mesh.primitives[p].targets.size() != n)
                fail(PF_ERR_PARSE, fmt("mesh %d: primitive %zu has %zu morph targets and primitive 0 has %zu (glTF "
                                       "2.0 Sec. 3.7.2.2: every primitive of a mesh has the same number)",
                                       mi, p, mesh.primitives[p].targets.size(), n));
        if (n > PF_ANIM_MAX_TARGETS)
            fail(PF_ERR_UNSUPPORTED, fmt("mesh %d has %zu morph targets; softgi reads at most %u", mi, n,
                                         PF_ANIM_MAX_TARGETS));
        return uint32_t(n);
    }

    /* The static weights of node `ni` (node.weights, else mesh.weights, else 0). */
    void node_weights(int ni, pf_anim_node *an)
    {
        const tinygltf::Node &n = m.nodes[size_t(ni)];
        const tinygltf::Mesh &mesh = m.meshes[size_t(n.mesh)];
        const uint32_t count = mesh_targets(n.mesh);
        if (!n.weights.empty() && n.weights.size() != count)
            fail(PF_ERR_PARSE, fmt("node %d: weights has %zu numbers, but its mesh %d has %u morph targets", ni,
                                   n.weights.size(), n.mesh, count));
        if (!mesh.weights.empty() && mesh.weights.size() != count)
            fail(PF_ERR_PARSE, fmt("mesh %d: weights has %zu numbers, but it has %u morph targets", n.mesh,
                                   mesh.weights.size(), count));
        if (!count) return;
        take(uint64_t(count) * 8, fmt("node %d's morph weights", ni));
        an->weight_count = count;
        an->rest_weights = alloc<float>(count);
        an->weights = alloc<float>(count);
        const std::vector<double> &w = !n.weights.empty() ? n.weights : mesh.weights;
        for (uint32_t k = 0; k < count && !w.empty(); k++) {
            if (!std::isfinite(float(w[k])))
                fail(PF_ERR_NONFINITE, fmt("node %d: morph weight %u (%g) is not finite", ni, k, w[k]));
            an->rest_weights[k] = float(w[k]);
        }
    }

    /* The nodes as the walk left them: order (parents first), parents, the
     * static transforms; the mesh nodes' weights and the skins they use. */
    void nodes(const std::vector<int> &order, const std::vector<int> &parent, const std::vector<pf_anim_node> &rest)
    {
        const size_t n = m.nodes.size();
        take(uint64_t(n) * (sizeof(pf_anim_node) + sizeof(pf_mat4) + 10 * sizeof(double)) + order.size() * 4,
             "the node hierarchy");
        a.node_count = uint32_t(n);
        a.nodes = alloc<pf_anim_node>(n);
        a.world = alloc<pf_mat4>(n);
        a.trs = alloc<double>(n * 10);
        a.order = alloc<uint32_t>(order.size());
        a.order_count = uint32_t(order.size());
        a.skin_count = uint32_t(m.skins.size());
        a.skins = alloc<pf_anim_skin>(m.skins.size());
        for (size_t i = 0; i < n; i++) {
            pf_anim_node &an = a.nodes[i];
            an = rest[i];
            an.weight_count = 0, an.rest_weights = an.weights = nullptr;
            an.parent = parent[i];
            a.world[i] = pf_mat4_identity();
        }
        for (size_t o = 0; o < order.size(); o++) {
            const int ni = order[o];
            a.order[o] = uint32_t(ni);
            a.nodes[ni].in_scene = 1;
            const tinygltf::Node &nd = m.nodes[size_t(ni)];
            if (nd.mesh < 0) continue;
            if (size_t(nd.mesh) >= m.meshes.size())
                fail(PF_ERR_INDEX_RANGE, fmt("node %d uses mesh %d, but the file has %zu", ni, nd.mesh, m.meshes.size()));
            node_weights(ni, &a.nodes[ni]);
            if (nd.skin < 0) continue;
            if (size_t(nd.skin) >= m.skins.size())
                fail(PF_ERR_INDEX_RANGE, fmt("node %d uses skin %d, but the file has %zu", ni, nd.skin, m.skins.size()));
            a.skins[nd.skin].used = 1;
        }
    }

    /* ------------------------------------------------ skins */

    void skin(int si)
    {
        const tinygltf::Skin &gs = m.skins[size_t(si)];
        pf_anim_skin &sk = a.skins[si];
        if (gs.joints.empty()) fail(PF_ERR_PARSE, fmt("skin %d has no joints", si));
        if (gs.joints.size() > PF_ANIM_MAX_JOINTS)
            fail(PF_ERR_UNSUPPORTED,
                 fmt("skin %d has %zu joints; softgi reads at most %u", si, gs.joints.size(), PF_ANIM_MAX_JOINTS));
        const size_t nj = gs.joints.size();
        take(uint64_t(nj) * (4 + 2 * sizeof(pf_mat4)), fmt("skin %d's %zu joints", si, nj));
        sk.joints = alloc<uint32_t>(nj);
        sk.ibm = alloc<pf_mat4>(nj);
        sk.joint_mats = alloc<pf_mat4>(nj);
        sk.joint_count = uint32_t(nj);
        for (size_t j = 0; j < nj; j++) {
            const int node = gs.joints[j];
            if (node < 0 || size_t(node) >= m.nodes.size())
                fail(PF_ERR_INDEX_RANGE,
                     fmt("skin %d: joint %zu is node %d, but the file has %zu", si, j, node, m.nodes.size()));
            if (!a.nodes[node].in_scene)
                fail(PF_ERR_PARSE, fmt("skin %d: joint %zu is node %d, which is not in the scene", si, j, node));
            sk.joints[j] = uint32_t(node);
            sk.ibm[j] = pf_mat4_identity();
        }
        if (gs.inverseBindMatrices < 0) return; /* identity (glTF 2.0 Sec. 3.7.3.1) */
        std::string what = fmt("skin %d inverseBindMatrices", si);
        std::vector<float> F = read_floats(m, gs.inverseBindMatrices, 16, kFloat, implicit_limit, what);
        if (F.size() / 16 < nj)
            fail(PF_ERR_ACCESSOR, fmt("skin %d: inverseBindMatrices has %zu matrices for %zu joints", si,
                                      F.size() / 16, nj));
        for (size_t j = 0; j < nj; j++)
            for (int e = 0; e < 16; e++) {
                const float v = F[j * 16 + size_t(e)];
                if (!std::isfinite(v))
                    fail(PF_ERR_NONFINITE, fmt("skin %d: inverse bind matrix %zu is not finite", si, j));
                sk.ibm[j].m[e] = v;
            }
    }

    /* ------------------------------------------------ animations */

    static pf_anim_interp interpolation(const std::string &s, const std::string &where)
    {
        if (s == "LINEAR") return PF_ANIM_LINEAR;
        if (s == "STEP") return PF_ANIM_STEP;
        if (s == "CUBICSPLINE") return PF_ANIM_CUBICSPLINE;
        fail(PF_ERR_PARSE, fmt("%s: interpolation '%.40s' (glTF 2.0 has LINEAR, STEP and CUBICSPLINE)", where.c_str(),
                               s.c_str()));
    }

    /* Sampler `gs` read for `path` with `dim` floats per value: times finite,
     * >= 0, strictly increasing, at most PF_ANIM_MAX_TIME; values finite,
     * exactly as many as the keys need (glTF 2.0 Sec. 3.11, Appendix C). */
    void sampler(const tinygltf::AnimationSampler &gs, pf_anim_path path, uint32_t dim, const std::string &where,
                 pf_anim_sampler *out)
    {
        out->interp = interpolation(gs.interpolation, where);
        out->dim = dim;
        const int ncomp = path == PF_ANIM_WEIGHTS ? 1 : int(dim);
        const tinygltf::Accessor &in = get_accessor(m, gs.input, where + " input");
        const tinygltf::Accessor &ou = get_accessor(m, gs.output, where + " output");
        take((uint64_t(in.count) + uint64_t(ou.count) * uint64_t(ncomp)) * 4,
             fmt("%s's %zu keys", where.c_str(), in.count));
        std::vector<float> T = read_floats(m, gs.input, 1, kFloat, implicit_limit, where + " input");
        if (T.empty()) fail(PF_ERR_ACCESSOR, where + ": the input accessor has no keys");
        for (size_t k = 0; k < T.size(); k++) {
            if (!std::isfinite(T[k]) || T[k] < 0.0f || double(T[k]) > PF_ANIM_MAX_TIME)
                fail(PF_ERR_NONFINITE, fmt("%s: input time %zu is %g; times are finite seconds in 0..%g", where.c_str(),
                                           k, double(T[k]), PF_ANIM_MAX_TIME));
            if (k > 0 && !(T[k] > T[k - 1]))
                fail(PF_ERR_PARSE, fmt("%s: input time %zu (%g) is not after time %zu (%g); times must increase "
                                       "strictly",
                                       where.c_str(), k, double(T[k]), k - 1, double(T[k - 1])));
        }
        const Components comps = path == PF_ANIM_ROTATION || path == PF_ANIM_WEIGHTS ? kFloatOrNormalized : kFloat;
        std::vector<float> V = read_floats(m, gs.output, ncomp, comps, implicit_limit, where + " output");
        const int cubic = out->interp == PF_ANIM_CUBICSPLINE;
        const uint64_t want = uint64_t(T.size()) * (cubic ? 3u : 1u) * dim;
        if (uint64_t(V.size()) != want)
            fail(PF_ERR_ACCESSOR, fmt("%s: output has %zu numbers, but %zu keys need %llu (%s%s)", where.c_str(),
                                      V.size(), T.size(), (unsigned long long)want,
                                      cubic ? "in-tangent, value and out-tangent per key" : "one value per key",
                                      path == PF_ANIM_WEIGHTS ? fmt(", %u weights each", dim).c_str() : ""));
        for (size_t i = 0; i < V.size(); i++)
            if (!std::isfinite(V[i]))
                fail(PF_ERR_NONFINITE, fmt("%s: output value %zu (key %zu) is not finite", where.c_str(), i,
                                           i / (dim * (cubic ? 3u : 1u))));
        if (path == PF_ANIM_ROTATION)
            for (size_t k = 0; k < T.size(); k++) {
                const float *q = &V[(k * (cubic ? 3u : 1u) + (cubic ? 1u : 0u)) * 4];
                if (q[0] == 0.0f && q[1] == 0.0f && q[2] == 0.0f && q[3] == 0.0f)
                    fail(PF_ERR_NONFINITE, fmt("%s: rotation key %zu is the zero quaternion", where.c_str(), k));
            }
        out->times = alloc<float>(T.size());
        memcpy(out->times, T.data(), T.size() * sizeof(float));
        out->values = alloc<float>(V.size());
        memcpy(out->values, V.data(), V.size() * sizeof(float));
        out->key_count = uint32_t(T.size());
    }

    static bool parse_path(const std::string &s, pf_anim_path *p)
    {
        if (s == "translation") *p = PF_ANIM_TRANSLATION;
        else if (s == "rotation") *p = PF_ANIM_ROTATION;
        else if (s == "scale") *p = PF_ANIM_SCALE;
        else if (s == "weights") *p = PF_ANIM_WEIGHTS;
        else return false;
        return true;
    }

    /* Channel ci of animation ai into clip c, or nothing when it moves
     * nothing the scene shows. */
    void channel(size_t ai, size_t ci, pf_anim_clip *c, std::vector<std::pair<int, int>> *seen)
    {
        const tinygltf::Animation &ga = m.animations[ai];
        const tinygltf::AnimationChannel &ch = ga.channels[ci];
        std::string where = fmt("animation %zu channel %zu", ai, ci);
        if (ch.target_node < 0) {
            warn(where + ": no target node (KHR_animation_pointer is not read): ignored");
            return;
        }
        if (size_t(ch.target_node) >= m.nodes.size())
            fail(PF_ERR_INDEX_RANGE,
                 fmt("%s targets node %d, but the file has %zu", where.c_str(), ch.target_node, m.nodes.size()));
        pf_anim_path path;
        if (!parse_path(ch.target_path, &path)) {
            if (ch.target_path == "pointer") {
                warn(where + ": path 'pointer' (KHR_animation_pointer) is not read: ignored");
                return;
            }
            fail(PF_ERR_PARSE, fmt("%s: target path '%.40s' (glTF 2.0 has translation, rotation, scale and weights)",
                                   where.c_str(), ch.target_path.c_str()));
        }
        const std::pair<int, int> target(ch.target_node, int(path));
        for (const std::pair<int, int> &s : *seen)
            if (s == target)
                fail(PF_ERR_PARSE, fmt("%s: node %d's %s is animated twice in one animation (glTF 2.0 Sec. 3.11)",
                                       where.c_str(), ch.target_node, ch.target_path.c_str()));
        seen->push_back(target);
        if (ch.sampler < 0 || size_t(ch.sampler) >= ga.samplers.size())
            fail(PF_ERR_INDEX_RANGE, fmt("%s uses sampler %d, but animation %zu has %zu", where.c_str(), ch.sampler, ai,
                                         ga.samplers.size()));
        const pf_anim_node &node = a.nodes[ch.target_node];
        if (path != PF_ANIM_WEIGHTS && !m.nodes[size_t(ch.target_node)].matrix.empty())
            fail(PF_ERR_PARSE, fmt("%s animates node %d's %s, but node %d has a matrix (glTF 2.0 Sec. 3.11: an "
                                   "animated node has translation, rotation and scale)",
                                   where.c_str(), ch.target_node, ch.target_path.c_str(), ch.target_node));
        if (!node.in_scene) return; /* moves nothing the scene shows */
        if (path == PF_ANIM_WEIGHTS && node.weight_count == 0)
            fail(PF_ERR_PARSE, fmt("%s animates node %d's morph weights, but its mesh has no morph targets",
                                   where.c_str(), ch.target_node));
        const uint32_t dim = path == PF_ANIM_WEIGHTS ? node.weight_count : path == PF_ANIM_ROTATION ? 4u : 3u;
        const int use = int(path) << 16 | int(dim);
        int &used = sampler_use[size_t(ch.sampler)];
        if (used == 0) {
            sampler(ga.samplers[size_t(ch.sampler)], path, dim, fmt("animation %zu sampler %d", ai, ch.sampler),
                    &c->samplers[ch.sampler]);
            used = use;
        } else if (used != use) {
            fail(PF_ERR_ACCESSOR, fmt("%s: sampler %d also animates a %s of %d numbers", where.c_str(), ch.sampler,
                                      (used >> 16) == PF_ANIM_WEIGHTS ? "weights" : "transform", used & 0xffff));
        }
        pf_anim_channel &out = c->channels[c->channel_count++];
        out.sampler = uint32_t(ch.sampler);
        out.node = uint32_t(ch.target_node);
        out.path = path;
        (path == PF_ANIM_WEIGHTS ? weights_animated : trs_animated)[size_t(ch.target_node)] = 1;
    }

    void animations()
    {
        trs_animated.assign(m.nodes.size(), 0);
        weights_animated.assign(m.nodes.size(), 0);
        const size_t n = m.animations.size();
        take(uint64_t(n) * sizeof(pf_anim_clip), "the animations");
        a.clips = alloc<pf_anim_clip>(n);
        a.clip_count = uint32_t(n);
        for (size_t ai = 0; ai < n; ai++) {
            const tinygltf::Animation &ga = m.animations[ai];
            pf_anim_clip &c = a.clips[ai];
            snprintf(c.name, sizeof c.name, "%s", ga.name.c_str());
            take(uint64_t(ga.samplers.size()) * sizeof(pf_anim_sampler) +
                     uint64_t(ga.channels.size()) * sizeof(pf_anim_channel),
                 fmt("animation %zu", ai));
            c.samplers = alloc<pf_anim_sampler>(ga.samplers.size());
            c.sampler_count = uint32_t(ga.samplers.size());
            c.channels = alloc<pf_anim_channel>(ga.channels.size());
            sampler_use.assign(ga.samplers.size(), 0);
            std::vector<std::pair<int, int>> seen;
            for (size_t ci = 0; ci < ga.channels.size(); ci++) channel(ai, ci, &c, &seen);
            c.start = c.end = 0.0f;
            bool any = false;
            for (uint32_t s = 0; s < c.sampler_count; s++) {
                const pf_anim_sampler &sm = c.samplers[s];
                if (!sm.key_count) continue;
                const float t0 = sm.times[0], t1 = sm.times[sm.key_count - 1];
                c.start = !any || t0 < c.start ? t0 : c.start;
                c.end = !any || t1 > c.end ? t1 : c.end;
                any = true;
            }
        }
    }

    /* ------------------------------------------------ the whole set-up, before the primitives */

    void setup(const std::vector<int> &order, const std::vector<int> &parent, const std::vector<pf_anim_node> &rest)
    {
        nodes(order, parent, rest);
        for (size_t si = 0; si < m.skins.size(); si++)
            if (a.skins[si].used) skin(int(si));
        animations();
        /* what an animation can move: a node whose TRS or an ancestor's is animated */
        moves.assign(m.nodes.size(), 0);
        for (uint32_t o = 0; o < a.order_count; o++) {
            const uint32_t ni = a.order[o];
            const int p = a.nodes[ni].parent;
            moves[ni] = trs_animated[ni] || (p >= 0 && moves[size_t(p)]);
        }
        skin_moves.assign(m.skins.size(), 0);
        for (size_t si = 0; si < m.skins.size(); si++)
            for (uint32_t j = 0; j < a.skins[si].joint_count && !skin_moves[si]; j++)
                skin_moves[si] = moves[a.skins[si].joints[j]];
        pf_anim_evaluate(&a, PF_ANIM_STATIC, 0.0); /* the static pose the primitives are flattened in */
    }

    /* ------------------------------------------------ primitives */

    /* JOINTS_n / WEIGHTS_n of a skinned primitive (glTF 2.0 Sec. 3.7.3.3). */
    void skin_attributes(const tinygltf::Primitive &p, size_t nv, const std::string &what, pf_anim_prim *ap)
    {
        const pf_anim_skin &sk = a.skins[ap->skin];
        uint32_t sets = 0;
        while (sets < PF_ANIM_MAX_SETS && p.attributes.count(fmt("JOINTS_%u", sets))) sets++;
        if (sets == PF_ANIM_MAX_SETS && p.attributes.count(fmt("JOINTS_%u", sets)))
            fail(PF_ERR_UNSUPPORTED, what + fmt(": more than %u JOINTS_n sets", PF_ANIM_MAX_SETS));
        if (sets == 0)
            fail(PF_ERR_ACCESSOR, what + fmt(": node %u uses skin %d, but the primitive has no JOINTS_0 (glTF 2.0 "
                                              "Sec. 3.7.3.3: a skinned primitive has JOINTS_0 and WEIGHTS_0)",
                                              ap->node, ap->skin));
        if (p.attributes.count(fmt("WEIGHTS_%u", sets)))
            fail(PF_ERR_ACCESSOR, what + fmt(": WEIGHTS_%u without JOINTS_%u", sets, sets));
        const size_t per = size_t(4) * sets;
        take(uint64_t(nv) * per * 6, what + " joints and weights");
        ap->joint_sets = sets;
        ap->joint = alloc<uint16_t>(nv * per);
        ap->weight = alloc<float>(nv * per);
        for (uint32_t s = 0; s < sets; s++) {
            auto wt = p.attributes.find(fmt("WEIGHTS_%u", s));
            if (wt == p.attributes.end()) fail(PF_ERR_ACCESSOR, what + fmt(": JOINTS_%u without WEIGHTS_%u", s, s));
            std::vector<float> J = read_floats(m, p.attributes.at(fmt("JOINTS_%u", s)), 4, kJointIndex,
                                               implicit_limit, what + fmt(" JOINTS_%u", s));
            std::vector<float> W = read_floats(m, wt->second, 4, kFloatOrUnorm, implicit_limit,
                                               what + fmt(" WEIGHTS_%u", s));
            if (J.size() != nv * 4 || W.size() != nv * 4)
                fail(PF_ERR_ACCESSOR, what + fmt(": JOINTS_%u or WEIGHTS_%u count differs from POSITION count", s, s));
            for (size_t v = 0; v < nv; v++)
                for (size_t k = 0; k < 4; k++) {
                    const float j = J[v * 4 + k], w = W[v * 4 + k];
                    if (!(j < float(sk.joint_count)))
                        fail(PF_ERR_INDEX_RANGE, what + fmt(": JOINTS_%u of vertex %zu names joint %g, but skin %d "
                                                            "has %u joints",
                                                            s, v, double(j), ap->skin, sk.joint_count));
                    if (!std::isfinite(w))
                        fail(PF_ERR_NONFINITE, what + fmt(": WEIGHTS_%u of vertex %zu is not finite", s, v));
                    ap->joint[v * per + s * 4 + k] = uint16_t(j);
                    ap->weight[v * per + s * 4 + k] = w;
                }
        }
    }

    /* POSITION and NORMAL deltas of the morph targets (TANGENT is not read). */
    void targets(const tinygltf::Primitive &p, size_t nv, const std::string &what, pf_anim_prim *ap)
    {
        bool any_pos = false, any_nrm = false;
        for (const std::map<std::string, int> &tg : p.targets) {
            any_pos |= tg.count("POSITION") != 0;
            any_nrm |= !ap->flat && tg.count("NORMAL") != 0;
        }
        take(uint64_t(nv) * ap->target_count * 12 * (uint64_t(any_pos) + uint64_t(any_nrm)),
             what + " morph targets");
        if (any_pos) ap->target_pos = alloc<pf_vec3>(nv * ap->target_count);
        if (any_nrm) ap->target_nrm = alloc<pf_vec3>(nv * ap->target_count);
        for (uint32_t k = 0; k < ap->target_count; k++)
            for (const auto &attr : p.targets[k]) {
                pf_vec3 *dst = attr.first == "POSITION" ? ap->target_pos
                               : attr.first == "NORMAL" ? ap->target_nrm
                                                        : nullptr;
                if (!dst) continue;
                std::string w = what + fmt(" target %u %s", k, attr.first.c_str());
                std::vector<float> D = read_floats(m, attr.second, 3, kFloat, implicit_limit, w);
                if (D.size() != nv * 3) fail(PF_ERR_ACCESSOR, w + ": count differs from POSITION count");
                for (size_t v = 0; v < nv; v++) {
                    const pf_vec3 d = pf_v3(D[3 * v], D[3 * v + 1], D[3 * v + 2]);
                    if (!pf_v3_is_finite(d)) fail(PF_ERR_NONFINITE, w + fmt(" %zu is not finite", v));
                    dst[size_t(k) * nv + v] = d;
                }
            }
    }

    /* What deforms the primitive (its node's skin, its morph targets),
     * whether an animation can move it, and its own data when either needs
     * them. Returns whether it is deformed (posed by pf_anim_prim_deform). */
    bool prepare(const tinygltf::Primitive &p, int node, const std::vector<float> &P, const std::vector<float> &N,
                 const std::string &what, pf_anim_prim *ap)
    {
        const size_t nv = P.size() / 3;
        const tinygltf::Node &nd = m.nodes[size_t(node)];
        ap->target_count = a.nodes[node].weight_count; /* = p.targets.size() (mesh_targets) */
        ap->skin = nd.skin >= 0 ? nd.skin : -1;
        ap->flat = N.empty();
        const bool deformed = ap->skin >= 0 || ap->target_count > 0;
        ap->dynamic = (ap->target_count && weights_animated[size_t(node)]) ||
                      (ap->skin >= 0 ? skin_moves[size_t(ap->skin)] : moves[size_t(node)]);
        if (!deformed && !(ap->dynamic && keep)) return false;
        take(uint64_t(nv) * (ap->flat ? 12 : 24), what + " (kept for posing)");
        ap->local_count = uint32_t(nv);
        ap->local_pos = alloc<pf_vec3>(nv);
        if (nv) memcpy(ap->local_pos, P.data(), nv * sizeof(pf_vec3));
        if (!ap->flat) {
            ap->local_nrm = alloc<pf_vec3>(nv);
            if (nv) memcpy(ap->local_nrm, N.data(), nv * sizeof(pf_vec3));
        }
        if (ap->skin >= 0) skin_attributes(p, nv, what, ap);
        if (ap->target_count) targets(p, nv, what, ap);
        return deformed;
    }

    /* The primitive flattened: kept (its place, and its data when dynamic)
     * or let go. */
    void finish(pf_anim_prim *ap, std::vector<uint32_t> *src)
    {
        if (!keep) {
            pf_anim_prim_free(ap);
            return;
        }
        if (!ap->dynamic) {
            pf_anim_prim_free(ap);
            ap->local_count = 0;
            ap->target_count = ap->joint_sets = 0;
        } else if (ap->flat) {
            take(uint64_t(src->size()) * 4, "a flat primitive's corners");
            ap->src = alloc<uint32_t>(src->size());
            if (!src->empty()) /* empty when every triangle was dropped (found by fuzz_gltf) */
                memcpy(ap->src, src->data(), src->size() * sizeof(uint32_t));
        }
        prims.push_back(*ap);
        memset(ap, 0, sizeof *ap); /* owned by `prims` now */
    }

    /* Hands the pf_anim to the caller (keep) or frees it. */
    void release(pf_anim *out)
    {
        if (!keep || a.clip_count == 0) return; /* no animation: nothing to pose, nothing kept */
        uint32_t max_local = 0, dynamic = 0;
        for (const pf_anim_prim &p : prims) {
            dynamic += p.dynamic != 0;
            if (p.dynamic && p.local_count > max_local) max_local = p.local_count;
        }
        take(uint64_t(prims.size()) * sizeof(pf_anim_prim) + uint64_t(max_local) * 24, "posing's scratch");
        a.scratch_pos = alloc<pf_vec3>(max_local);
        a.scratch_nrm = alloc<pf_vec3>(max_local);
        a.prims = alloc<pf_anim_prim>(prims.size());
        if (!prims.empty()) memcpy(a.prims, prims.data(), prims.size() * sizeof(pf_anim_prim));
        a.prim_count = uint32_t(prims.size());
        prims.clear();
        a.dynamic_count = dynamic;
        a.max_local = max_local;
        a.pose_clip = PF_ANIM_STATIC;
        a.pose_time = 0.0;
        *out = a;
        memset(&a, 0, sizeof a);
    }
};

/* ---------------------------------------------------------------- builder */

struct Builder {
    const tinygltf::Model &m;
    const pf_gltf_options &opts;
    std::string name;
    size_t implicit_limit; /* see kImplicitPerByte */
    std::vector<pf_vec3> pos, nrm;
    std::vector<pf_vec2> uv;
    std::vector<uint32_t> idx, tri_mat;
    std::vector<pf_camera> cameras;
    std::vector<pf_light> lights;
    std::string warnings;
    uint32_t dropped = 0;
    int default_material = -1; /* index of the glTF default material, made on demand */
    size_t skipped_prims = 0;
    const pf_budget *budget = nullptr; /* triangles are checked against it as they are added */
    AnimReader *anim = nullptr;        /* skins, morph targets, what posing keeps */
    /* the walk (walk_nodes): the scene's nodes in visiting order, each one's
     * parent (-1: a root), static transform and world matrix */
    std::vector<int> order{}, parent{};
    std::vector<pf_anim_node> rest{};
    std::vector<pf_mat4> world{};

    void warn(const std::string &w)
    {
        if (warnings.size() < 900) warnings += w + "\n";
    }

    uint32_t material_for(int mat)
    {
        if (mat < 0) {
            if (default_material < 0) default_material = int(m.materials.size());
            return uint32_t(default_material);
        }
        if (size_t(mat) >= m.materials.size())
            fail(PF_ERR_INDEX_RANGE,
                 fmt("a mesh primitive uses material %d, but the file has %zu", mat, m.materials.size()));
        return uint32_t(mat);
    }

    void add_primitive(const tinygltf::Primitive &p, const pf_mat4 &world, int mesh_index, size_t prim_index,
                       int node_index)
    {
        std::string what = fmt("mesh %d primitive %zu", mesh_index, prim_index);
        int mode = p.mode < 0 ? TINYGLTF_MODE_TRIANGLES : p.mode;
        if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
            mode != TINYGLTF_MODE_TRIANGLE_FAN) {
            if (mode >= 0 && mode <= 3) {
                skipped_prims++;
                warn(what + ": points/lines primitive skipped");
                return;
            }
            fail(PF_ERR_PARSE, what + fmt(": unknown primitive mode %d", mode));
        }
        auto pit = p.attributes.find("POSITION");
        if (pit == p.attributes.end()) {
            skipped_prims++;
            warn(what + ": no POSITION, skipped");
            return;
        }
        uint32_t material = material_for(p.material);
        std::vector<float> P = read_floats(m, pit->second, 3, kFloat, implicit_limit, what + " POSITION");
        size_t nv = P.size() / 3;
        std::vector<float> N, T;
        auto nit = p.attributes.find("NORMAL");
        if (nit != p.attributes.end()) {
            N = read_floats(m, nit->second, 3, kFloat, implicit_limit, what + " NORMAL");
            if (N.size() != P.size()) fail(PF_ERR_ACCESSOR, what + ": NORMAL count differs from POSITION count");
        }
        auto tit = p.attributes.find("TEXCOORD_0");
        if (tit != p.attributes.end()) {
            T = read_floats(m, tit->second, 2, kFloatOrNormalized, implicit_limit, what + " TEXCOORD_0");
            if (T.size() / 2 != nv) fail(PF_ERR_ACCESSOR, what + ": TEXCOORD_0 count differs from POSITION count");
        }
        std::vector<uint32_t> I;
        if (p.indices >= 0) {
            I = read_indices(m, p.indices, what + " indices");
            for (size_t i = 0; i < I.size(); i++)
                if (I[i] >= nv)
                    fail(PF_ERR_INDEX_RANGE, what + fmt(": index %u at position %zu is out of range (%zu vertices)",
                                                        I[i], i, nv));
        } else {
            I.resize(nv);
            for (size_t i = 0; i < nv; i++) I[i] = uint32_t(i);
        }
        /* Expand to a triangle list (glTF 2.0 Sec. 3.7.2.1 primitive modes). */
        std::vector<uint32_t> L;
        if (mode == TINYGLTF_MODE_TRIANGLES) {
            if (I.size() % 3) warn(what + ": index count is not a multiple of 3; the remainder is ignored");
            L.assign(I.begin(), I.begin() + ptrdiff_t(I.size() - I.size() % 3));
        } else if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
            for (size_t i = 2; i < I.size(); i++) {
                bool odd = (i & 1) != 0; /* keep every triangle counter-clockwise */
                L.push_back(I[i - 2]);
                L.push_back(odd ? I[i] : I[i - 1]);
                L.push_back(odd ? I[i - 1] : I[i]);
            }
        } else {
            for (size_t i = 2; i < I.size(); i++) {
                L.push_back(I[0]);
                L.push_back(I[i - 1]);
                L.push_back(I[i]);
            }
        }
        if (idx.size() / 3 + L.size() / 3 > kMaxSceneTriangles)
            fail(PF_ERR_UNSUPPORTED, fmt("the scene instances more than %zu triangles", kMaxSceneTriangles));
        if (budget) { /* checked as the instances add up, before the arrays grow */
            pf_budget trial = *budget;
            uint64_t tris = idx.size() / 3 + L.size() / 3;
            pf_error e;
            if (pf_budget_take(&trial, pf_budget_mul(tris, PF_BUDGET_BYTES_PER_TRIANGLE),
                               fmt("the scene's %llu triangles (after instancing)", (unsigned long long)tris).c_str(),
                               &e) != PF_OK)
                fail(e.code, e.message);
        }

        for (size_t v = 0; v < N.size() / 3; v++)
            if (!std::isfinite(N[3 * v]) || !std::isfinite(N[3 * v + 1]) || !std::isfinite(N[3 * v + 2]))
                fail(PF_ERR_NONFINITE, what + fmt(": NORMAL %zu is not finite", v));
        for (size_t v = 0; v < T.size(); v++)
            if (!std::isfinite(T[v])) fail(PF_ERR_NONFINITE, what + fmt(": TEXCOORD_0 %zu is not finite", v / 2));
        for (size_t v = 0; v < nv; v++)
            if (!pf_v3_is_finite(pf_v3(P[3 * v], P[3 * v + 1], P[3 * v + 2])))
                fail(PF_ERR_NONFINITE, what + fmt(": POSITION %zu is not finite", v));

        /* Skin and morph targets (pf_anim.h): a deformed primitive is
         * flattened in the static pose by the code that poses it later. */
        pf_anim_prim ap;
        memset(&ap, 0, sizeof ap);
        ap.node = uint32_t(node_index), ap.mesh = uint32_t(mesh_index), ap.prim = uint32_t(prim_index);
        struct PrimGuard {
            pf_anim_prim *p;
            ~PrimGuard() { pf_anim_prim_free(p); }
        } prim_guard{&ap};
        const bool deformed = anim->prepare(p, node_index, P, N, what, &ap);
        const bool mirror = ap.skin < 0 && pf_mat4_det3(&world) < 0.0; /* skinned: the file's winding */
        const bool flat = N.empty();
        /* World-space positions (and, deformed, normals) of this primitive. */
        std::vector<pf_vec3> WP(nv), WN(deformed && !flat ? nv : 0);
        uint32_t bad = UINT32_MAX;
        if (deformed) {
            bad = pf_anim_prim_deform(&anim->a, &ap, WP.data(), flat ? nullptr : WN.data());
        } else {
            for (size_t v = 0; v < nv && bad == UINT32_MAX; v++) {
                WP[v] = pf_mat4_point(&world, pf_v3(P[3 * v], P[3 * v + 1], P[3 * v + 2]));
                if (!pf_scene_coord_ok(WP[v])) bad = uint32_t(v);
            }
        }
        if (bad != UINT32_MAX)
            fail(PF_ERR_NONFINITE, what + fmt(": POSITION %u lands at (%g, %g, %g), beyond the supported range |x| <= %g",
                                              bad, double(WP[bad].x), double(WP[bad].y), double(WP[bad].z),
                                              double(PF_SCENE_MAX_COORD)));

        /* Vertex ids of this primitive in the scene arrays (welded case). */
        uint32_t base = uint32_t(pos.size());
        const size_t first_tri = idx.size() / 3;
        std::vector<uint32_t> src; /* flat and kept for posing: the file vertex of each corner */
        const bool want_src = flat && anim->keep && ap.dynamic;
        if (!flat) {
            for (size_t v = 0; v < nv; v++) {
                pos.push_back(WP[v]);
                pf_vec3 n;
                if (deformed) {
                    n = WN[v];
                } else {
                    n = pf_mat4_normal(&world, pf_v3(N[3 * v], N[3 * v + 1], N[3 * v + 2]));
                    n = pf_anim_unit(n); /* posing's rule (pf_anim.h): zero where not finite */
                    if (mirror) n = pf_v3_scale(n, -1.0f); /* cofactor = det * M^-T */
                }
                nrm.push_back(n); /* zero normals fixed below */
                uv.push_back(T.empty() ? pf_vec2{0, 0} : pf_vec2{T[2 * v], T[2 * v + 1]});
            }
        }
        for (size_t t = 0; t + 2 < L.size(); t += 3) {
            uint32_t a = L[t], b = L[t + 1], c = L[t + 2];
            if (mirror) std::swap(b, c);
            pf_vec3 fn = pf_v3_cross(pf_v3_sub(WP[b], WP[a]), pf_v3_sub(WP[c], WP[a]));
            if (a == b || b == c || a == c || (fn.x == 0.0f && fn.y == 0.0f && fn.z == 0.0f)) {
                dropped++;
                continue;
            }
            fn = pf_anim_unit(fn);
            if (flat) {
                /* a face normal too small to normalise (only without DAZ,
                 * which drops such a triangle above): (0, 1, 0), as posing */
                const pf_vec3 face = fn.x == 0.0f && fn.y == 0.0f && fn.z == 0.0f ? pf_v3(0, 1, 0) : fn;
                const uint32_t abc[3] = {a, b, c};
                for (uint32_t k : abc) {
                    idx.push_back(uint32_t(pos.size()));
                    pos.push_back(WP[k]);
                    nrm.push_back(face);
                    uv.push_back(T.empty() ? pf_vec2{0, 0} : pf_vec2{T[2 * k], T[2 * k + 1]});
                    if (want_src) src.push_back(k);
                }
            } else {
                const uint32_t abc[3] = {a, b, c};
                for (uint32_t k : abc) {
                    pf_vec3 &n = nrm[base + k];
                    if (n.x == 0.0f && n.y == 0.0f && n.z == 0.0f) n = fn; /* zero-length NORMAL in the file */
                    idx.push_back(base + k);
                }
            }
            tri_mat.push_back(material);
        }
        /* Zero normals on vertices no kept triangle uses: any unit vector. */
        if (!flat)
            for (size_t v = base; v < nrm.size(); v++)
                if (nrm[v].x == 0.0f && nrm[v].y == 0.0f && nrm[v].z == 0.0f) nrm[v] = pf_v3(0, 1, 0);
        /* where it lies in the scene, for posing */
        ap.vertex_first = base;
        ap.vertex_count = uint32_t(pos.size() - base);
        ap.tri_first = uint32_t(first_tri);
        ap.tri_count = uint32_t(idx.size() / 3 - first_tri);
        ap.mirror = mirror;
        anim->finish(&ap, &src);
    }

    void add_camera(int cam_index, const pf_mat4 &world, int node_index)
    {
        if (cam_index < 0) return;
        if (size_t(cam_index) >= m.cameras.size())
            fail(PF_ERR_INDEX_RANGE,
                 fmt("node %d uses camera %d, but the file has %zu", node_index, cam_index, m.cameras.size()));
        const tinygltf::Camera &c = m.cameras[size_t(cam_index)];
        if (c.type != "perspective") {
            warn(fmt("camera %d is '%s'; only perspective cameras are used", cam_index, c.type.c_str()));
            return;
        }
        pf_camera cam;
        memset(&cam, 0, sizeof cam);
        snprintf(cam.name, sizeof cam.name, "%s", c.name.empty() ? "camera" : c.name.c_str());
        cam.eye = pf_mat4_point(&world, pf_v3(0, 0, 0));
        cam.forward = pf_v3_normalize_safe(pf_mat4_dir(&world, pf_v3(0, 0, -1)));
        pf_vec3 up = pf_mat4_dir(&world, pf_v3(0, 1, 0));
        cam.right = pf_v3_normalize_safe(pf_v3_cross(cam.forward, up));
        cam.up = pf_v3_cross(cam.right, cam.forward);
        if (pf_v3_length(cam.forward) == 0.0f || pf_v3_length(cam.right) == 0.0f)
            fail(PF_ERR_NONFINITE, fmt("camera %d: its node transform is degenerate", cam_index));
        cam.yfov = float(c.perspective.yfov);
        cam.znear = float(c.perspective.znear);
        cam.zfar = float(c.perspective.zfar);
        cam.aspect = float(c.perspective.aspectRatio);
        if (!(cam.yfov > 0.0f && cam.yfov < PF_PI))
            fail(PF_ERR_PARSE, fmt("camera %d: yfov %g is outside (0, pi)", cam_index, c.perspective.yfov));
        if (!(cam.znear > 0.0f) || !std::isfinite(cam.znear)) cam.znear = 0.01f;
        if (!(cam.zfar > cam.znear) || !std::isfinite(cam.zfar)) cam.zfar = 0.0f;
        if (!(cam.aspect > 0.0f) || !std::isfinite(cam.aspect)) cam.aspect = 0.0f;
        cameras.push_back(cam);
    }

    void add_light(const tinygltf::Node &n, const pf_mat4 &world, int node_index)
    {
        auto it = n.extensions.find("KHR_lights_punctual");
        if (it == n.extensions.end()) return;
        const tinygltf::Value &v = it->second;
        if (!v.IsObject() || !v.Has("light") || !v.Get("light").IsNumber())
            fail(PF_ERR_PARSE, fmt("node %d: KHR_lights_punctual needs a 'light' index", node_index));
        double lid = v.Get("light").GetNumberAsDouble(); /* checked as double: no int overflow */
        if (!(lid >= 0.0) || lid >= double(m.lights.size()) || lid != std::floor(lid))
            fail(PF_ERR_INDEX_RANGE,
                 fmt("node %d uses light %g, but the file has %zu", node_index, lid, m.lights.size()));
        int li = int(lid);
        const tinygltf::Light &L = m.lights[size_t(li)];
        pf_light out;
        memset(&out, 0, sizeof out);
        snprintf(out.name, sizeof out.name, "%s", L.name.empty() ? "light" : L.name.c_str());
        if (L.type == "point") out.type = PF_LIGHT_POINT;
        else if (L.type == "spot") out.type = PF_LIGHT_SPOT;
        else if (L.type == "directional") out.type = PF_LIGHT_DIRECTIONAL;
        else fail(PF_ERR_PARSE, fmt("light %d has unknown type '%s'", li, L.type.c_str()));
        out.position = pf_mat4_point(&world, pf_v3(0, 0, 0));
        out.direction = pf_v3_normalize_safe(pf_mat4_dir(&world, pf_v3(0, 0, -1)));
        if (out.type != PF_LIGHT_POINT && pf_v3_length(out.direction) == 0.0f)
            fail(PF_ERR_NONFINITE, fmt("light %d: its node transform has no direction", li));
        out.color = pf_v3(1, 1, 1);
        if (!L.color.empty()) {
            if (L.color.size() != 3) fail(PF_ERR_PARSE, fmt("light %d: color must have 3 numbers", li));
            out.color = pf_v3(float(L.color[0]), float(L.color[1]), float(L.color[2]));
        }
        out.intensity = float(L.intensity);
        out.range = float(L.range);
        if (out.type == PF_LIGHT_SPOT) {
            out.inner_cone = float(L.spot.innerConeAngle);
            out.outer_cone = float(L.spot.outerConeAngle);
        }
        /* KHR_lights_punctual: colour in [0, 1] (clamped, with a warning),
         * intensity >= 0; their product must stay far from float overflow
         * (PF_MAX_RADIANCE), or shading turns it into inf and NaN. */
        bool clamped = false;
        float *rgb[3] = {&out.color.x, &out.color.y, &out.color.z};
        for (float *c : rgb) {
            float cc = *c < 0.0f ? 0.0f : *c > 1.0f ? 1.0f : *c;
            clamped |= cc != *c && std::isfinite(*c);
            if (std::isfinite(*c)) *c = cc;
        }
        if (clamped) warn(fmt("light %d: color outside [0, 1] clamped", li));
        if (!(L.intensity >= 0.0) || L.intensity > double(PF_MAX_RADIANCE))
            fail(PF_ERR_NONFINITE, fmt("light %d: intensity %g is outside [0, %g]", li, L.intensity,
                                       double(PF_MAX_RADIANCE)));
        if (out.range > 0.0f) warn(fmt("light %d: range is ignored (softgi uses pure 1/r^2 falloff)", li));
        lights.push_back(out);
    }

    /* Pass 1: the node forest from the scene's roots, depth first in file
     * order (explicit stack, cycle and depth checks): order, parents,
     * static transforms and world matrices. */
    void walk_nodes(const std::vector<int> &roots)
    {
        struct Item {
            int node;
            int depth;
            int parent;
        };
        std::vector<Item> stack;
        /* Roots are pushed in reverse so nodes are visited in file order. */
        for (size_t i = roots.size(); i-- > 0;) stack.push_back({roots[i], 0, -1});
        std::vector<int> path_depth(m.nodes.size(), -1); /* depth at which a node is on the current path */
        std::vector<char> seen(m.nodes.size(), 0);       /* glTF nodes form disjoint trees */
        std::vector<int> path;                           /* nodes on the path, by depth */
        parent.assign(m.nodes.size(), -1);
        world.assign(m.nodes.size(), pf_mat4_identity());
        rest.resize(m.nodes.size());
        for (pf_anim_node &r : rest) {
            memset(&r, 0, sizeof r);
            r.matrix = pf_mat4_identity();
            r.r[3] = 1.0, r.s[0] = r.s[1] = r.s[2] = 1.0;
        }
        while (!stack.empty()) {
            Item it = stack.back();
            stack.pop_back();
            if (it.node < 0 || size_t(it.node) >= m.nodes.size())
                fail(PF_ERR_INDEX_RANGE, fmt("a scene or node refers to node %d, but the file has %zu", it.node,
                                             m.nodes.size()));
            if (it.depth > kMaxNodeDepth)
                fail(PF_ERR_PARSE, fmt("the node hierarchy is deeper than %d", kMaxNodeDepth));
            while (int(path.size()) > it.depth) {
                path_depth[size_t(path.back())] = -1;
                path.pop_back();
            }
            if (path_depth[size_t(it.node)] >= 0)
                fail(PF_ERR_PARSE, fmt("node %d is its own ancestor (a cycle in the node hierarchy)", it.node));
            if (seen[size_t(it.node)])
                fail(PF_ERR_PARSE, fmt("node %d has more than one parent or is listed twice (glTF nodes form trees)",
                                       it.node));
            seen[size_t(it.node)] = 1;
            path_depth[size_t(it.node)] = it.depth;
            path.push_back(it.node);

            const tinygltf::Node &n = m.nodes[size_t(it.node)];
            pf_mat4 local = node_local(n, it.node, &rest[size_t(it.node)]);
            const pf_mat4 up = it.parent >= 0 ? world[size_t(it.parent)] : pf_mat4_identity();
            world[size_t(it.node)] = pf_mat4_mul(&up, &local);
            parent[size_t(it.node)] = it.parent;
            order.push_back(it.node);
            for (size_t c = n.children.size(); c-- > 0;) stack.push_back({n.children[c], it.depth + 1, it.node});
        }
    }

    /* Pass 2, in the walk's order: every node's mesh primitives, camera and
     * light, flattened into world space. */
    void add_nodes()
    {
        for (int node : order) {
            const tinygltf::Node &n = m.nodes[size_t(node)];
            const pf_mat4 &w = world[size_t(node)];
            if (n.mesh >= 0) {
                if (size_t(n.mesh) >= m.meshes.size())
                    fail(PF_ERR_INDEX_RANGE,
                         fmt("node %d uses mesh %d, but the file has %zu", node, n.mesh, m.meshes.size()));
                const tinygltf::Mesh &mesh = m.meshes[size_t(n.mesh)];
                for (size_t p = 0; p < mesh.primitives.size(); p++)
                    add_primitive(mesh.primitives[p], w, n.mesh, p, node);
            }
            add_camera(n.camera, w, node);
            add_light(n, w, node);
        }
    }
};

pf_wrap wrap_mode(int gl)
{
    if (gl == TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE) return PF_WRAP_CLAMP;
    if (gl == TINYGLTF_TEXTURE_WRAP_MIRRORED_REPEAT) return PF_WRAP_MIRROR;
    return PF_WRAP_REPEAT;
}

/* The encoded bytes of image `index` (a checked bufferView, or the uri's
 * file or data read by tinygltf). */
void image_bytes(const tinygltf::Model &m, int index, const unsigned char **bytes, size_t *size)
{
    const tinygltf::Image &img = m.images[size_t(index)];
    const char *label = img.uri.empty() ? img.name.c_str() : img.uri.c_str();
    if (img.bufferView >= 0) {
        if (size_t(img.bufferView) >= m.bufferViews.size())
            fail(PF_ERR_INDEX_RANGE, fmt("image %d refers to bufferView %d, but the file has %zu", index,
                                         img.bufferView, m.bufferViews.size()));
        *size = m.bufferViews[size_t(img.bufferView)].byteLength;
        if (*size == 0) fail(PF_ERR_TEXTURE, fmt("image %d: bufferView %d is empty", index, img.bufferView));
        *bytes = checked_view(m, img.bufferView, 0, 1, *size, fmt("image %d", index)).base;
    } else {
        if (img.image.empty())
            fail(PF_ERR_TEXTURE, fmt("image %d ('%.200s') could not be loaded: file missing or empty", index, label));
        *bytes = img.image.data();
        *size = img.image.size();
    }
}

/* Header only: the decoded size of image `index`, before anything is
 * decoded (pf_decode_probe applies softgi's per-image limits). */
void probe_image(const tinygltf::Model &m, int index, uint32_t *w, uint32_t *h)
{
    const unsigned char *bytes;
    size_t size;
    image_bytes(m, index, &bytes, &size);
    pf_image_format f;
    pf_error e;
    if (pf_decode_probe(bytes, size, nullptr, &f, w, h, &e) != PF_OK) {
        const tinygltf::Image &img = m.images[size_t(index)];
        fail(e.code, fmt("image %d ('%.200s'): %s", index, img.uri.empty() ? img.name.c_str() : img.uri.c_str(),
                         e.message));
    }
}

/* Decodes image `index` to RGBA8 (PNG through libspng, JPEG through
 * libjpeg-turbo: pf_decode.h). The caller frees the result. */
uint8_t *decode_image(const tinygltf::Model &m, int index, uint32_t *w, uint32_t *h)
{
    const unsigned char *bytes;
    size_t size;
    image_bytes(m, index, &bytes, &size);
    uint8_t *rgba = nullptr;
    pf_error e;
    if (pf_decode_rgba8(bytes, size, nullptr, &rgba, w, h, &e) != PF_OK) {
        const tinygltf::Image &img = m.images[size_t(index)];
        fail(e.code, fmt("image %d ('%.200s'): %s", index, img.uri.empty() ? img.name.c_str() : img.uri.c_str(),
                         e.message));
    }
    return rgba;
}

template <typename T> T *copy_out(const std::vector<T> &v, size_t extra = 0)
{
    size_t n = v.size() + extra;
    T *p = static_cast<T *>(calloc(n ? n : 1, sizeof(T)));
    if (!p) throw std::bad_alloc();
    if (!v.empty()) memcpy(p, v.data(), v.size() * sizeof(T));
    return p;
}

/* A camera whose near plane lies beyond every triangle, or whose far plane
 * lies before them all, renders an empty image: refused with the distances
 * rather than rendered black without a word. */
void check_camera_ranges(const std::vector<pf_camera> &cams, const std::vector<pf_vec3> &pos)
{
    if (pos.empty()) return;
    pf_vec3 lo = pos[0], hi = pos[0];
    for (const pf_vec3 &p : pos) {
        lo = pf_v3_min(lo, p);
        hi = pf_v3_max(hi, p);
    }
    for (size_t c = 0; c < cams.size(); c++) {
        const pf_camera &cam = cams[c];
        double far2 = 0.0, near2 = 0.0;
        const float e[3] = {cam.eye.x, cam.eye.y, cam.eye.z}, l[3] = {lo.x, lo.y, lo.z}, h[3] = {hi.x, hi.y, hi.z};
        for (int k = 0; k < 3; k++) {
            double a = fabs(double(e[k]) - l[k]), bb = fabs(double(e[k]) - h[k]);
            far2 += (a > bb ? a : bb) * (a > bb ? a : bb);
            double d = e[k] < l[k] ? double(l[k]) - e[k] : e[k] > h[k] ? double(e[k]) - h[k] : 0.0;
            near2 += d * d;
        }
        if (double(cam.znear) >= sqrt(far2))
            fail(PF_ERR_PARSE, fmt("camera %zu: znear %g lies beyond the whole scene (its farthest point is %g away): "
                                   "the image would be empty",
                                   c, double(cam.znear), sqrt(far2)));
        if (cam.zfar > 0.0f && double(cam.zfar) <= sqrt(near2))
            fail(PF_ERR_PARSE, fmt("camera %zu: zfar %g lies before the whole scene (its nearest point is %g away): "
                                   "the image would be empty",
                                   c, double(cam.zfar), sqrt(near2)));
    }
}

void build_scene(pf_scene *out, const tinygltf::Model &m, const pf_gltf_options &opts, const std::string &name,
                 std::string warnings_in, size_t input_bytes, pf_budget *budget)
{
    size_t limit = input_bytes > (SIZE_MAX / kImplicitPerByte) ? SIZE_MAX : input_bytes * kImplicitPerByte;
    Builder b{m, opts, name, limit > kImplicitFloor ? limit : kImplicitFloor, {}, {}, {}, {}, {}, {}, {}, {}, 0, -1, 0};
    b.warnings = warnings_in.size() > 400 ? warnings_in.substr(0, 400) : warnings_in;

    std::vector<int> roots;
    if (m.defaultScene >= 0 || !m.scenes.empty()) {
        int si = m.defaultScene >= 0 ? m.defaultScene : 0;
        if (size_t(si) >= m.scenes.size())
            fail(PF_ERR_INDEX_RANGE, fmt("default scene %d does not exist (the file has %zu)", si, m.scenes.size()));
        roots = m.scenes[size_t(si)].nodes;
    } else {
        std::vector<char> is_child(m.nodes.size(), 0);
        for (const tinygltf::Node &n : m.nodes)
            for (int c : n.children)
                if (c >= 0 && size_t(c) < m.nodes.size()) is_child[size_t(c)] = 1;
        for (size_t i = 0; i < m.nodes.size(); i++)
            if (!is_child[i]) roots.push_back(int(i));
    }
    b.budget = budget;
    AnimReader anim(m, b.implicit_limit, budget, opts.anim != nullptr, &b.warnings);
    b.anim = &anim;
    b.walk_nodes(roots);
    anim.setup(b.order, b.parent, b.rest);
    b.add_nodes();
    check_camera_ranges(b.cameras, b.pos);
    {
        pf_error e;
        uint64_t tris = b.idx.size() / 3;
        if (pf_budget_take(budget, pf_budget_mul(tris, PF_BUDGET_BYTES_PER_TRIANGLE),
                           fmt("the scene's %llu triangles", (unsigned long long)tris).c_str(), &e) != PF_OK)
            fail(e.code, e.message);
    }
    /* what posing needs, for the caller (pf_gltf_options.anim) */
    pf_anim kept;
    memset(&kept, 0, sizeof kept);
    kept.pose_clip = PF_ANIM_STATIC;
    struct AnimGuard {
        pf_anim *a;
        bool keep;
        ~AnimGuard()
        {
            if (!keep) pf_anim_free(a);
        }
    } anim_guard{&kept, false};
    anim.release(&kept);

    /* Materials: the file's, plus the glTF default material if used. */
    size_t nmat = m.materials.size() + (b.default_material >= 0 ? 1 : 0);
    std::vector<pf_material> mats(nmat);
    std::vector<int> tex_used(m.textures.size(), -1); /* glTF texture -> pf texture */
    std::vector<pf_texture> textures;
    std::vector<int> img_used(m.images.size(), -1);
    std::vector<int> img_order;
    for (size_t i = 0; i < nmat; i++) {
        pf_material &pm = mats[i];
        memset(&pm, 0, sizeof pm);
        pm.base_color[0] = pm.base_color[1] = pm.base_color[2] = pm.base_color[3] = 1.0f;
        pm.base_color_texture = -1;
        pm.alpha_cutoff = 0.5f;
        if (i == m.materials.size()) {
            snprintf(pm.name, sizeof pm.name, "gltf-default");
            continue;
        }
        const tinygltf::Material &gm = m.materials[i];
        snprintf(pm.name, sizeof pm.name, "%s", gm.name.c_str());
        /* glTF 2.0 puts every baseColorFactor and emissiveFactor component in
         * [0, 1]: outside it a material reflects more light than it
         * receives (energy grows with every bounce) or a negative amount.
         * Clamped, with a warning. */
        const std::vector<double> &bc = gm.pbrMetallicRoughness.baseColorFactor;
        if (bc.size() == 4) {
            bool clamped = false;
            for (int k = 0; k < 4; k++) {
                double c = bc[size_t(k)];
                double cc = c < 0.0 ? 0.0 : c > 1.0 ? 1.0 : c;
                clamped |= cc != c;
                pm.base_color[k] = float(cc);
            }
            if (clamped) b.warn(fmt("material %zu: baseColorFactor outside [0, 1] clamped", i));
        } else if (!bc.empty())
            fail(PF_ERR_PARSE, fmt("material %zu: baseColorFactor must have 4 numbers", i));
        if (gm.emissiveFactor.size() == 3) {
            double strength = 1.0;
            auto ext = gm.extensions.find("KHR_materials_emissive_strength");
            if (ext != gm.extensions.end() && ext->second.Has("emissiveStrength") &&
                ext->second.Get("emissiveStrength").IsNumber())
                strength = ext->second.Get("emissiveStrength").GetNumberAsDouble();
            if (!(strength >= 0.0) || strength > double(PF_MAX_RADIANCE))
                fail(PF_ERR_NONFINITE, fmt("material %zu: emissiveStrength %g is outside [0, %g]", i, strength,
                                           double(PF_MAX_RADIANCE)));
            bool clamped = false;
            for (int k = 0; k < 3; k++) {
                double c = gm.emissiveFactor[size_t(k)];
                double cc = c < 0.0 ? 0.0 : c > 1.0 ? 1.0 : c;
                clamped |= cc != c;
                pm.emission[k] = float(cc * strength);
            }
            if (clamped) b.warn(fmt("material %zu: emissiveFactor outside [0, 1] clamped", i));
        }
        if (gm.alphaMode == "MASK") pm.alpha_mode = PF_ALPHA_MASK;
        else if (gm.alphaMode == "BLEND") {
            pm.alpha_mode = PF_ALPHA_BLEND;
            b.warn(fmt("material %zu: alphaMode BLEND is rendered as OPAQUE", i));
        }
        pm.alpha_cutoff = float(gm.alphaCutoff);
        pm.double_sided = gm.doubleSided ? 1 : 0;
        int ti = gm.pbrMetallicRoughness.baseColorTexture.index;
        if (ti >= 0 && !opts.ignore_textures) {
            if (size_t(ti) >= m.textures.size())
                fail(PF_ERR_INDEX_RANGE, fmt("material %zu uses texture %d, but the file has %zu", i, ti,
                                             m.textures.size()));
            if (gm.pbrMetallicRoughness.baseColorTexture.texCoord != 0)
                b.warn(fmt("material %zu: baseColorTexture uses TEXCOORD_%d; softgi reads TEXCOORD_0", i,
                           gm.pbrMetallicRoughness.baseColorTexture.texCoord));
            if (tex_used[size_t(ti)] < 0) {
                const tinygltf::Texture &gt = m.textures[size_t(ti)];
                if (gt.source < 0 || size_t(gt.source) >= m.images.size())
                    fail(PF_ERR_TEXTURE, fmt("texture %d has image source %d, but the file has %zu images", ti,
                                             gt.source, m.images.size()));
                pf_texture t;
                memset(&t, 0, sizeof t);
                t.mag_linear = 1;
                t.min_linear = 1;
                t.min_mipmap = 1;
                t.mip_linear = 1;
                if (gt.sampler >= 0) {
                    if (size_t(gt.sampler) >= m.samplers.size())
                        fail(PF_ERR_INDEX_RANGE, fmt("texture %d uses sampler %d, but the file has %zu", ti,
                                                     gt.sampler, m.samplers.size()));
                    const tinygltf::Sampler &s = m.samplers[size_t(gt.sampler)];
                    t.wrap_s = wrap_mode(s.wrapS);
                    t.wrap_t = wrap_mode(s.wrapT);
                    t.mag_linear = s.magFilter != TINYGLTF_TEXTURE_FILTER_NEAREST;
                    switch (s.minFilter) {
                    case TINYGLTF_TEXTURE_FILTER_NEAREST: t.min_linear = 0; t.min_mipmap = 0; break;
                    case TINYGLTF_TEXTURE_FILTER_LINEAR: t.min_linear = 1; t.min_mipmap = 0; break;
                    case TINYGLTF_TEXTURE_FILTER_NEAREST_MIPMAP_NEAREST: t.min_linear = 0; t.mip_linear = 0; break;
                    case TINYGLTF_TEXTURE_FILTER_LINEAR_MIPMAP_NEAREST: t.min_linear = 1; t.mip_linear = 0; break;
                    case TINYGLTF_TEXTURE_FILTER_NEAREST_MIPMAP_LINEAR: t.min_linear = 0; t.mip_linear = 1; break;
                    default: break; /* LINEAR_MIPMAP_LINEAR or unset */
                    }
                }
                if (img_used[size_t(gt.source)] < 0) {
                    img_used[size_t(gt.source)] = int(img_order.size());
                    img_order.push_back(gt.source);
                }
                t.image = uint32_t(img_used[size_t(gt.source)]);
                tex_used[size_t(ti)] = int(textures.size());
                textures.push_back(t);
            }
            pm.base_color_texture = tex_used[size_t(ti)];
        }
    }

    /* Decode and mip-map the images the materials use. */
    std::vector<pf_image> images(img_order.size());
    for (pf_image &im : images) memset(&im, 0, sizeof im);
    struct ImageGuard {
        std::vector<pf_image> &v;
        bool keep = false;
        ~ImageGuard()
        {
            if (!keep)
                for (pf_image &im : v) free(im.texels);
        }
    } guard{images};
    /* Memory first, from the headers alone: every image's texels and mips
     * (4/3 of level 0) stay; one decode at a time is transient: its level 0
     * (4 bytes a texel) and, for a progressive JPEG, libjpeg's whole-image
     * coefficient buffer (up to 6 bytes a texel at 4:4:4), so 3x level 0. */
    uint64_t largest = 0, texel_bytes = 0;
    for (size_t i = 0; i < img_order.size(); i++) {
        uint32_t w, h;
        probe_image(m, img_order[i], &w, &h);
        uint64_t level0 = uint64_t(w) * h * 4;
        largest = level0 > largest ? level0 : largest;
        texel_bytes += level0 + level0 / 3 + 64;
        pf_error e;
        if (pf_budget_take(budget, level0 + level0 / 3 + 64,
                           fmt("image %d (%ux%u texels and mips)", img_order[i], w, h).c_str(), &e) != PF_OK)
            fail(e.code, e.message);
    }
    {
        pf_error e;
        if (pf_budget_take(budget, pf_budget_mul(largest, 3), "decoding the largest image", &e) != PF_OK)
            fail(e.code, e.message);
        budget->used -= pf_budget_mul(largest, 3); /* transient: given back once decoding is over */
    }
    for (size_t i = 0; i < img_order.size(); i++) {
        uint32_t w, h;
        uint8_t *rgba = decode_image(m, img_order[i], &w, &h);
        pf_error e;
        pf_result r = pf_image_build_mips(&images[i], rgba, w, h, &e);
        free(rgba);
        if (r != PF_OK) fail(e.code, e.message);
    }

    if (b.idx.empty()) {
        if (b.dropped)
            fail(PF_ERR_NO_TRIANGLES, fmt("all %u triangles are degenerate (zero area)", b.dropped));
        fail(PF_ERR_NO_TRIANGLES, "the scene has no triangles to render");
    }

    /* Hand everything to C. */
    pf_scene s;
    memset(&s, 0, sizeof s);
    try {
        s.vertex_count = uint32_t(b.pos.size());
        s.positions = copy_out(b.pos, 1);
        s.normals = copy_out(b.nrm);
        s.uvs = copy_out(b.uv);
        s.tri_count = uint32_t(b.idx.size() / 3);
        s.indices = copy_out(b.idx);
        s.tri_material = copy_out(b.tri_mat);
        s.material_count = uint32_t(mats.size());
        s.materials = copy_out(mats);
        s.texture_count = uint32_t(textures.size());
        s.textures = copy_out(textures);
        s.image_count = uint32_t(images.size());
        s.images = copy_out(images);
        s.camera_count = uint32_t(b.cameras.size());
        s.cameras = copy_out(b.cameras);
        s.light_count = uint32_t(b.lights.size());
        s.lights = copy_out(b.lights);
    } catch (...) {
        s.image_count = 0; /* texels still owned by the guard */
        pf_scene_free(&s);
        throw;
    }
    guard.keep = true;
    s.dropped_degenerate = b.dropped;
    s.memory_bytes = pf_budget_mul(s.tri_count, PF_BUDGET_BYTES_PER_TRIANGLE) + texel_bytes + kept.memory_bytes;
    if (b.dropped) b.warn(fmt("%u zero-area triangles dropped", b.dropped));
    snprintf(s.warnings, sizeof s.warnings, "%s", b.warnings.c_str());
    pf_error e;
    if (pf_scene_validate(&s, &e) != PF_OK) {
        pf_scene_free(&s);
        fail(e.code, e.message);
    }
    *out = s;
    if (opts.anim) {
        *opts.anim = kept;
        anim_guard.keep = true;
    }
}

std::string first_line(const std::string &s)
{
    std::string t = s.substr(0, s.find('\n'));
    return t.size() > 300 ? t.substr(0, 300) : t;
}

pf_result load(pf_scene *out, const unsigned char *data, size_t size, const char *base_dir, const char *name,
               const pf_gltf_options *opts_in, pf_error *err)
{
    memset(out, 0, sizeof *out);
    pf_gltf_options opts;
    memset(&opts, 0, sizeof opts);
    if (opts_in) opts = *opts_in;
    if (opts.anim) {
        memset(opts.anim, 0, sizeof *opts.anim);
        opts.anim->pose_clip = PF_ANIM_STATIC;
    }
    const char *nm = name ? name : "(memory)";
    if (size > 0xffffffffu) return pf_error_set(err, PF_ERR_UNSUPPORTED, "%s: files over 4 GiB are not supported", nm);
    if (size == 0) return pf_error_set(err, PF_ERR_PARSE, "%s: the file is empty", nm);
    try {
        pf_budget budget;
        pf_budget_init(&budget, opts.max_memory);
        pf_error be;
        if (pf_budget_take(&budget, size, "the scene file", &be) != PF_OK) fail(be.code, be.message);
        bool is_glb = size >= 4 && memcmp(data, "glTF", 4) == 0;
        const char *json;
        size_t json_size;
        json_of(data, size, is_glb, &json, &json_size);
        check_json(json, json_size);

        FsContext fsc;
        fsc.budget = &budget;
        if (base_dir) {
            char *rp = realpath(base_dir, nullptr);
            if (rp) {
                fsc.base_real = rp;
                free(rp);
                if (fsc.base_real.back() != '/') fsc.base_real += '/';
            }
        }
        tinygltf::TinyGLTF loader;
        tinygltf::FsCallbacks fs;
        fs.FileExists = fs_exists;
        fs.ExpandFilePath = fs_expand;
        fs.ReadWholeFile = fs_read;
        fs.WriteWholeFile = fs_write;
        fs.user_data = &fsc;
        loader.SetFsCallbacks(fs);
        loader.SetImageLoader(opts.ignore_textures ? skip_image : defer_image, nullptr);
        tinygltf::Model model;
        std::string terr, twarn;
        bool ok;
        std::string dir = base_dir ? base_dir : "";
        if (is_glb)
            ok = loader.LoadBinaryFromMemory(&model, &terr, &twarn, data, unsigned(size), dir);
        else
            ok = loader.LoadASCIIFromString(&model, &terr, &twarn, reinterpret_cast<const char *>(data),
                                            unsigned(size), dir);
        if (!ok) {
            std::string msg = first_line(terr.empty() ? twarn : terr);
            pf_result code = PF_ERR_PARSE;
            if (msg.find("File not found") != std::string::npos || msg.find("cannot open") != std::string::npos ||
                msg.find("Failed to load external") != std::string::npos)
                code = PF_ERR_IO;
            if (code == PF_ERR_IO)
                return pf_error_set(err, code, "%s: cannot read a file it refers to: %s", nm, msg.c_str());
            return pf_error_set(err, code, "%s: %s is not a loadable glTF 2.0 file: %s", nm, is_glb ? "binary" : "text",
                                msg.empty() ? "unknown tinygltf error" : msg.c_str());
        }
        size_t input_bytes = size;
        for (const tinygltf::Buffer &buf : model.buffers) input_bytes += buf.data.size();
        build_scene(out, model, opts, nm, twarn, input_bytes, &budget);
        return PF_OK;
    } catch (const LoadError &e) {
        return pf_error_set(err, e.code, "%s: %s", nm, e.message.c_str());
    } catch (const std::bad_alloc &) {
        return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "%s: out of memory while loading", nm);
    } catch (const std::exception &e) {
        return pf_error_set(err, PF_ERR_PARSE, "%s: %s", nm, e.what());
    }
}

} // namespace

extern "C" pf_result pf_gltf_load_memory(pf_scene *out, const void *data, size_t size, const char *base_dir,
                                         const char *name, const pf_gltf_options *opts, pf_error *err)
{
    return load(out, static_cast<const unsigned char *>(data), size, base_dir, name, opts, err);
}

extern "C" pf_result pf_gltf_load(pf_scene *out, const char *path, const pf_gltf_options *opts, pf_error *err)
{
    memset(out, 0, sizeof *out);
    if (opts && opts->anim) {
        memset(opts->anim, 0, sizeof *opts->anim);
        opts->anim->pose_clip = PF_ANIM_STATIC;
    }
    struct stat st;
    if (stat(path, &st) != 0) return pf_error_set(err, PF_ERR_IO, "%s: no such file", path);
    if (!S_ISREG(st.st_mode)) return pf_error_set(err, PF_ERR_IO, "%s: not a regular file", path);
    pf_budget budget; /* the file is read whole: its size counts before it is read (load() takes it again) */
    pf_budget_init(&budget, opts ? opts->max_memory : 0);
    std::vector<unsigned char> bytes;
    std::string ferr;
    if (!read_file(&bytes, &ferr, path, &budget))
        return pf_error_set(err, PF_ERR_IO, "%s: %s", path, first_line(ferr).c_str());
    std::string p(path);
    size_t slash = p.find_last_of('/');
    std::string dir = slash == std::string::npos ? std::string(".") : p.substr(0, slash == 0 ? 1 : slash);
    return load(out, bytes.data(), bytes.size(), dir.c_str(), path, opts, err);
}
