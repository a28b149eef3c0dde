/* fuzz_gltf: libFuzzer target for the glTF loader (pf_gltf.h).
 *
 * Feeds each input to pf_gltf_load_memory as the whole file (.gltf or .glb,
 * decided by content) with a real base folder, so external uris are
 * resolved and read, then frees the scene. The contract under test
 * (pf_gltf.h): any input gives PF_OK or a pf_error, never a crash, a leak,
 * an out-of-bounds access or undefined behaviour; a failed load leaves the
 * scene empty and says why; a successful one passes pf_scene_validate,
 * since the renderer trusts loaded scenes. The animations are kept
 * (pf_gltf_options.anim) and every animation posed at a few times
 * (check_poses): each pose succeeds with a valid scene of the same counts
 * and triangles, the same bits when repeated, or fails leaving the scene
 * as it was, and the static pose gives back the loaded bytes.
 *
 * And: the loader never opens a file outside its base folder. At start-up
 * the target makes
 *
 *   TMP/scene/       the base folder: a copy of tests/fuzz/seeds/gltf-base/
 *                    (buffer.bin, image.png, which the seeds' relative uris
 *                    name)
 *   TMP/secret.bin   canaries outside it, and copies of buffer.bin and
 *   TMP/buffer.bin   image.png, so that "../buffer.bin" names a file that
 *   TMP/image.png    exists
 *
 * and interposes fopen, fopen64, open, open64, openat and openat64: while
 * the loader runs, every path opened is resolved (realpath; a lexical
 * normalisation when the file does not exist) and the target aborts with a
 * message if it lies outside TMP/scene (except the few system files the
 * loader reads itself, kSystemFiles). "../scene/buffer.bin" is fine
 * (inside once resolved); "../buffer.bin", "%2e%2e/secret.bin" or a symlink
 * out of the folder are findings. libFuzzer's own file I/O (corpus,
 * artifacts) happens outside that window.
 *
 * Built by tests/fuzz/CMakeLists.txt against softgi_core compiled with
 * -fsanitize=fuzzer-no-link,address,undefined (tinygltf and stb_image
 * included); run with tools/fuzz.sh. */
#include <dirent.h>
#include <dlfcn.h>
#include <fcntl.h>
#include <limits.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdarg>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "pf_anim.h"
#include "pf_gltf.h"

#ifndef SOFTGI_FUZZ_SEEDS
#error "SOFTGI_FUZZ_SEEDS (tests/fuzz/seeds) is set by tests/fuzz/CMakeLists.txt"
#endif

namespace {

std::string g_tmp;          /* TMP */
std::string g_base;         /* realpath of TMP/scene, no trailing slash */
volatile int g_watch = 0;   /* 1 while the loader runs */
volatile int g_inside = 0;  /* re-entrancy guard: our own checks call realpath */

void remove_fixture();

/* ---------------------------------------------------------------- the check */

/* "/a/b/../c/./d" -> "/a/c/d" (no file-system access). */
std::string normalise(const std::string &abs)
{
    std::vector<std::string> parts;
    size_t i = 0;
    while (i <= abs.size()) {
        size_t j = abs.find('/', i);
        if (j == std::string::npos) j = abs.size();
        std::string p = abs.substr(i, j - i);
        if (p == "..") {
            if (!parts.empty()) parts.pop_back();
        } else if (!p.empty() && p != ".") {
            parts.push_back(p);
        }
        i = j + 1;
    }
    std::string out;
    for (const std::string &p : parts) out += "/" + p;
    return out.empty() ? "/" : out;
}

/* The absolute, resolved form of `path` (relative to the folder of `dirfd`,
 * or the working directory). */
std::string resolve(int dirfd, const char *path)
{
    std::string abs;
    if (path[0] == '/') {
        abs = path;
    } else {
        char dir[PATH_MAX];
        if (dirfd == AT_FDCWD) {
            if (!getcwd(dir, sizeof dir)) return std::string("?") + path;
        } else {
            char link[64];
            snprintf(link, sizeof link, "/proc/self/fd/%d", dirfd);
            ssize_t n = readlink(link, dir, sizeof dir - 1);
            if (n < 0) return std::string("?") + path;
            dir[n] = 0;
        }
        abs = std::string(dir) + "/" + path;
    }
    char real[PATH_MAX];
    if (realpath(abs.c_str(), real)) return real;
    /* The file does not exist: resolve its folder, normalise the rest. */
    std::string n = normalise(abs);
    size_t slash = n.find_last_of('/');
    std::string dir = slash == 0 ? "/" : n.substr(0, slash);
    if (realpath(dir.c_str(), real)) return normalise(std::string(real) + "/" + n.substr(slash + 1));
    return n;
}

/* Files the loader reads for its own purposes, not named by the input:
 * the memory budget's cgroup limits (pf_budget.c, pf_memory_machine).
 * Matched on the exact string the loader passes, so a uri that walks to
 * the same file ("../../sys/fs/cgroup/memory.max") is still a finding. */
const char *const kSystemFiles[] = {"/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes"};

void check_path(int dirfd, const char *path, const char *fn)
{
    if (!g_watch || g_inside || !path) return;
    for (const char *sys : kSystemFiles)
        if (strcmp(path, sys) == 0) return;
    g_inside = 1;
    std::string r = resolve(dirfd, path);
    bool inside = r == g_base || r.compare(0, g_base.size() + 1, g_base + "/") == 0;
    if (!inside) {
        fprintf(stderr,
                "\nfuzz_gltf: PATH TRAVERSAL: the loader called %s(\"%s\"), which resolves to '%s', outside its "
                "base folder '%s'\n",
                fn, path, r.c_str(), g_base.c_str());
        remove_fixture();
        abort();
    }
    g_inside = 0;
}

template <typename F> F real_fn(F &slot, const char *name)
{
    if (!slot) slot = reinterpret_cast<F>(dlsym(RTLD_NEXT, name));
    if (!slot) {
        fprintf(stderr, "fuzz_gltf: dlsym(RTLD_NEXT, %s) failed\n", name);
        abort();
    }
    return slot;
}

/* ---------------------------------------------------------------- fixture */

bool copy_file(const std::string &from, const std::string &to)
{
    FILE *in = fopen(from.c_str(), "rb");
    if (!in) return false;
    FILE *out = fopen(to.c_str(), "wb");
    if (!out) {
        fclose(in);
        return false;
    }
    char buf[4096];
    size_t n;
    bool ok = true;
    while ((n = fread(buf, 1, sizeof buf, in)) > 0) ok = ok && fwrite(buf, 1, n, out) == n;
    fclose(in);
    return fclose(out) == 0 && ok;
}

void remove_fixture()
{
    if (g_tmp.empty()) return;
    const char *sub[] = {"/scene", ""};
    for (const char *s : sub) {
        std::string d = g_tmp + s;
        if (DIR *dir = opendir(d.c_str())) {
            while (struct dirent *e = readdir(dir))
                if (strcmp(e->d_name, ".") && strcmp(e->d_name, "..")) unlink((d + "/" + e->d_name).c_str());
            closedir(dir);
        }
        rmdir(d.c_str());
    }
}

/* Fixtures of earlier runs that died (a crash skips atexit): their names
 * carry the pid, removed when that process is gone. */
void remove_stale_fixtures()
{
    DIR *dir = opendir("/tmp");
    if (!dir) return;
    while (struct dirent *e = readdir(dir)) {
        int pid = 0;
        if (sscanf(e->d_name, "softgi-fuzz-gltf-%d-", &pid) != 1 || pid <= 0) continue;
        if (kill(pid, 0) == 0 || errno != ESRCH) continue;
        std::string saved = g_tmp;
        g_tmp = std::string("/tmp/") + e->d_name;
        remove_fixture();
        g_tmp = saved;
    }
    closedir(dir);
}

void make_fixture()
{
    remove_stale_fixtures();
    char tmpl[64];
    snprintf(tmpl, sizeof tmpl, "/tmp/softgi-fuzz-gltf-%d-XXXXXX", (int)getpid());
    if (!mkdtemp(tmpl)) {
        perror("fuzz_gltf: mkdtemp");
        abort();
    }
    g_tmp = tmpl;
    std::string scene = g_tmp + "/scene";
    if (mkdir(scene.c_str(), 0700) != 0) {
        perror("fuzz_gltf: mkdir");
        abort();
    }
    std::string seeds = std::string(SOFTGI_FUZZ_SEEDS) + "/gltf-base";
    DIR *dir = opendir(seeds.c_str());
    if (!dir) {
        fprintf(stderr, "fuzz_gltf: cannot open the fixture folder %s\n", seeds.c_str());
        abort();
    }
    while (struct dirent *e = readdir(dir)) {
        if (e->d_name[0] == '.') continue;
        std::string from = seeds + "/" + e->d_name;
        /* the base folder, and a copy outside it under the same name */
        if (!copy_file(from, scene + "/" + e->d_name) || !copy_file(from, g_tmp + "/" + e->d_name)) {
            fprintf(stderr, "fuzz_gltf: cannot copy %s into %s\n", from.c_str(), g_tmp.c_str());
            abort();
        }
    }
    closedir(dir);
    FILE *canary = fopen((g_tmp + "/secret.bin").c_str(), "wb");
    if (!canary) abort();
    for (int i = 0; i < 256; i++) fputc(i, canary);
    fclose(canary);
    char real[PATH_MAX];
    if (!realpath(scene.c_str(), real)) abort();
    g_base = real;
    atexit(remove_fixture);
}

} // namespace

/* ---------------------------------------------------------------- interposers
 * Defined in the executable, so they come before libc's (and before the
 * sanitizers' weak interceptors of the same names) for every caller. */
extern "C" {

FILE *fopen(const char *path, const char *mode)
{
    static FILE *(*real)(const char *, const char *);
    check_path(AT_FDCWD, path, "fopen");
    return real_fn(real, "fopen")(path, mode);
}

FILE *fopen64(const char *path, const char *mode)
{
    static FILE *(*real)(const char *, const char *);
    check_path(AT_FDCWD, path, "fopen64");
    return real_fn(real, "fopen64")(path, mode);
}

#define FUZZ_GLTF_MODE(flags, mode)                                                                                   \
    do {                                                                                                              \
        if ((flags) & (O_CREAT | O_TMPFILE)) {                                                                        \
            va_list ap;                                                                                               \
            va_start(ap, flags);                                                                                      \
            mode = va_arg(ap, mode_t);                                                                                \
            va_end(ap);                                                                                               \
        }                                                                                                             \
    } while (0)

int open(const char *path, int flags, ...)
{
    static int (*real)(const char *, int, ...);
    mode_t mode = 0;
    FUZZ_GLTF_MODE(flags, mode);
    check_path(AT_FDCWD, path, "open");
    return real_fn(real, "open")(path, flags, mode);
}

int open64(const char *path, int flags, ...)
{
    static int (*real)(const char *, int, ...);
    mode_t mode = 0;
    FUZZ_GLTF_MODE(flags, mode);
    check_path(AT_FDCWD, path, "open64");
    return real_fn(real, "open64")(path, flags, mode);
}

int openat(int dirfd, const char *path, int flags, ...)
{
    static int (*real)(int, const char *, int, ...);
    mode_t mode = 0;
    FUZZ_GLTF_MODE(flags, mode);
    check_path(dirfd, path, "openat");
    return real_fn(real, "openat")(dirfd, path, flags, mode);
}

int openat64(int dirfd, const char *path, int flags, ...)
{
    static int (*real)(int, const char *, int, ...);
    mode_t mode = 0;
    FUZZ_GLTF_MODE(flags, mode);
    check_path(dirfd, path, "openat64");
    return real_fn(real, "openat64")(dirfd, path, flags, mode);
}

int LLVMFuzzerInitialize(int *, char ***)
{
    make_fixture();
    return 0;
}

/* The pose contract (pf_anim.h) on a loaded scene: every pose succeeds or
 * fails with PF_ERR_NONFINITE leaving the scene as it was; a posed scene
 * validates with the same counts and triangles; the static pose gives back
 * the loaded bytes; the same time twice, the same bytes. */
void check_poses(pf_scene *scene, pf_anim *anim)
{
    const size_t nv = scene->vertex_count, nt = scene->tri_count;
    std::vector<pf_vec3> p0(scene->positions, scene->positions + nv), n0(scene->normals, scene->normals + nv);
    std::vector<uint32_t> i0(scene->indices, scene->indices + 3 * nt);
    const double end = pf_anim_end(anim, PF_ANIM_ALL);
    const double times[] = {0.0, 0.37 * end, 0.5 * end, end, end + 1.0, 3.0};
    std::vector<pf_anim_moved> moved(anim->prim_count + 1);
    for (int32_t clip = PF_ANIM_ALL; clip < int32_t(anim->clip_count) && clip < 4; clip++)
        for (double t : times) {
            std::vector<pf_vec3> before(scene->positions, scene->positions + nv);
            pf_error e = {};
            pf_result r = pf_anim_pose(scene, moved.data(), nullptr, anim, clip, t, &e);
            if (r != PF_OK) {
                if (r != PF_ERR_NONFINITE || !e.message[0] ||
                    memcmp(before.data(), scene->positions, nv * sizeof(pf_vec3))) {
                    fprintf(stderr, "fuzz_gltf: a failed pose (%d '%s') changed the scene\n", (int)r, e.message);
                    abort();
                }
                continue;
            }
            pf_error verr = {};
            if (scene->vertex_count != nv || scene->tri_count != nt ||
                memcmp(i0.data(), scene->indices, i0.size() * sizeof(uint32_t)) ||
                pf_scene_validate(scene, &verr) != PF_OK) {
                fprintf(stderr, "fuzz_gltf: clip %d at %g: the posed scene is broken: %s\n", clip, t, verr.message);
                abort();
            }
            std::vector<pf_vec3> at(scene->positions, scene->positions + nv);
            if (pf_anim_pose(scene, nullptr, nullptr, anim, clip, t, &e) != PF_OK ||
                memcmp(at.data(), scene->positions, nv * sizeof(pf_vec3))) {
                fprintf(stderr, "fuzz_gltf: clip %d at %g posed twice differs\n", clip, t);
                abort();
            }
        }
    pf_error e = {};
    if (pf_anim_pose(scene, nullptr, nullptr, anim, PF_ANIM_STATIC, 0.0, &e) != PF_OK ||
        memcmp(p0.data(), scene->positions, nv * sizeof(pf_vec3)) ||
        memcmp(n0.data(), scene->normals, nv * sizeof(pf_vec3))) {
        fprintf(stderr, "fuzz_gltf: the static pose differs from the loaded scene (%s)\n", e.message);
        abort();
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    pf_scene scene;
    pf_anim anim;
    pf_error err = {};
    pf_gltf_options opts = {};
    opts.anim = &anim;
    g_watch = 1;
    pf_result r = pf_gltf_load_memory(&scene, data, size, g_base.c_str(), "fuzz", &opts, &err);
    g_watch = 0;
    if (getenv("FUZZ_GLTF_VERBOSE"))
        fprintf(stderr, "fuzz_gltf: %s (%u triangles, %u images)\n", r == PF_OK ? "PF_OK" : err.message,
                scene.tri_count, scene.image_count);
    if (r == PF_OK) {
        /* the loader promises a valid scene: anything else is a bug */
        pf_error verr = {};
        if (pf_scene_validate(&scene, &verr) != PF_OK) {
            fprintf(stderr, "fuzz_gltf: loaded scene fails pf_scene_validate: %s\n", verr.message);
            abort();
        }
        check_poses(&scene, &anim);
    } else if (scene.tri_count != 0 || scene.positions != nullptr || scene.materials != nullptr ||
               err.message[0] == '\0' || anim.clip_count != 0 || anim.nodes != nullptr || anim.prims != nullptr) {
        fprintf(stderr, "fuzz_gltf: failed load (%d) left a non-empty scene or no message\n", (int)r);
        abort(); /* failure must leave *out empty and say why */
    }
    pf_anim_free(&anim);
    pf_scene_free(&scene);
    return 0;
}

} // extern "C"
