/* render_frame: one frame through softgi's C API (include/softgi/softgi.h).
 *
 *   render_frame [SCENE.gltf|SCENE.glb] [-o OUT.ppm] [--size WxH] [--method NAME] [--aa N]
 *                [--dump-stages DIR] [--hash]
 *
 * Loads SCENE (default: the Cornell box built into the library), renders
 * one frame with indirect light and writes it as a binary PPM (8-bit sRGB,
 * tone mapped at exposure 0, the PNG `softgi render` writes, without the
 * PNG encoder) and prints the time of every stage. --hash prints the
 * linear image's hash, which equals `softgi render --hash` with the same
 * scene, size, method and --aa. --dump-stages writes every stage of the
 * frame as a captioned picture (softgi_dump_stages), as `softgi render
 * --dump-stages DIR` does.
 *
 * Build against an installed softgi (docs/api.md):
 *   cc examples/render_frame.c -o render_frame \
 *      $(PKG_CONFIG_PATH=/tmp/softgi-prefix/lib/pkgconfig pkg-config --cflags --libs --static softgi)
 * or with CMake: examples/CMakeLists.txt. */
#include <softgi/softgi.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int usage(void)
{
    fprintf(stderr, "usage: render_frame [SCENE.gltf|SCENE.glb] [-o OUT.ppm] [--size WxH] [--method NAME] [--aa N] "
                    "[--dump-stages DIR] [--hash]\n");
    return 2;
}

/* A binary PPM (P6) from RGBA8. */
static int write_ppm(const char *path, const uint8_t *rgba, uint32_t w, uint32_t h)
{
    FILE *f = fopen(path, "wb");
    if (!f) return 0;
    int ok = fprintf(f, "P6\n%u %u\n255\n", w, h) > 0;
    for (size_t i = 0; ok && i < (size_t)w * h; i++) ok = fwrite(rgba + 4 * i, 1, 3, f) == 3;
    return fclose(f) == 0 && ok;
}

int main(int argc, char **argv)
{
    const char *scene = NULL, *out = "render_frame.ppm", *dump = NULL;
    softgi_desc desc = {0}; /* zero: the defaults of `softgi render` */
    int print_hash = 0;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "-o") && i + 1 < argc) out = argv[++i];
        else if (!strcmp(argv[i], "--size") && i + 1 < argc) {
            if (sscanf(argv[++i], "%ux%u", &desc.width, &desc.height) != 2) return usage();
        } else if (!strcmp(argv[i], "--method") && i + 1 < argc) desc.method = argv[++i];
        else if (!strcmp(argv[i], "--aa") && i + 1 < argc) {
            if (sscanf(argv[++i], "%u", &desc.aa) != 1) return usage(); /* jittered samples a pixel */
        } else if (!strcmp(argv[i], "--dump-stages") && i + 1 < argc) dump = argv[++i];
        else if (!strcmp(argv[i], "--hash")) print_hash = 1;
        else if (argv[i][0] == '-' || scene) return usage();
        else scene = argv[i];
    }

    softgi_error err;
    softgi_context *ctx = softgi_create(&desc, &err);
    if (!ctx) {
        fprintf(stderr, "render_frame: %s\n", err.message);
        return 1;
    }
    softgi_info info;
    float *rgb = NULL;
    uint8_t *rgba = NULL;
    int status = 1;
    if (softgi_load_scene(ctx, scene, &err) != SOFTGI_OK) goto fail;
    softgi_get_info(ctx, &info, NULL);
    if (info.auto_camera) /* as `softgi render` says in its notes (docs/scenes.md) */
        fprintf(stderr, "render_frame: note: the scene has no camera; framed from its bounds: eye %g,%g,%g\n",
                (double)info.camera.eye[0], (double)info.camera.eye[1], (double)info.camera.eye[2]);
    if (info.auto_light) fprintf(stderr, "render_frame: note: the scene has no lights; added a point light at the camera\n");

    rgb = malloc((size_t)info.width * info.height * 3 * sizeof *rgb);
    rgba = malloc((size_t)info.width * info.height * 4);
    if (!rgb || !rgba) {
        fprintf(stderr, "render_frame: out of memory\n");
        goto done;
    }
    softgi_target target = {.rgb = rgb, .rgba8 = rgba, .exposure = 0.0f};
    if (softgi_render(ctx, &target, &err) != SOFTGI_OK) goto fail;
    if (!write_ppm(out, rgba, info.width, info.height)) {
        fprintf(stderr, "render_frame: cannot write %s\n", out);
        goto done;
    }

    if (dump && softgi_dump_stages(ctx, dump, 0.0f, SOFTGI_DUMP_PNG, &err) != SOFTGI_OK) goto fail;

    softgi_get_info(ctx, &info, NULL);
    printf("render_frame: %s, %u triangles, %u lights, %ux%u, %u threads, isa %s, method %s, %u VPLs\n",
           scene ? scene : "built-in cornell-box", info.triangles, info.lights, info.width, info.height, info.threads,
           info.isa, info.method ? info.method : "none", info.vpls);
    softgi_timing t[64];
    uint32_t n = softgi_get_timings(ctx, t, 64);
    for (uint32_t i = 0; i < n && i < 64; i++) printf("  %-30s %9.2f ms\n", t[i].name, t[i].ms);
    if (print_hash)
        printf("hash %016llx\n", (unsigned long long)softgi_image_hash(rgb, info.width, info.height, 0));
    printf("wrote %s\n", out);
    status = 0;
    goto done;
fail:
    fprintf(stderr, "render_frame: %s\n", err.message);
done:
    free(rgb);
    free(rgba);
    softgi_destroy(ctx);
    return status;
}
