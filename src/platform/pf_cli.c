/* pf_cli: strict command-line parsing (see pf_cli.h). */
#include "pf_cli.h"
#include "pf_budget.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

void pf_cli_usage(FILE *out)
{
    fputs("usage: softgi render [SCENE.gltf|SCENE.glb] [options]\n"
          "       softgi reference [SCENE.gltf|SCENE.glb] [options]   (path-traced reference)\n"
          "       softgi view [SCENE.gltf|SCENE.glb] [options]        (interactive viewer and stage stepper;\n"
          "                                                           keys: H in the window)\n"
          "       softgi sequence SEQUENCE.json [options]             (render a camera/light sequence)\n"
          "       softgi bench frame [--threads N] [--frames N] [--scenes DIR] [--vpls N] [--tiles NxM]\n"
          "       softgi compare ...                                  (softgi compare --help)\n"
          "       softgi evaluate ...                                 (softgi evaluate --help)\n"
          "       softgi bench raster [--threads N] [--frames N] [--scenes DIR] [--isa ISA]\n"
          "\n"
          "Renders SCENE (default: the embedded Cornell box) to a PNG and a linear\n"
          "HDR .pfm, printing per-stage timings.\n"
          "\n"
          "options:\n"
          "  -o, --output FILE       by extension: FILE.png writes the PNG and the linear PFM\n"
          "                          beside it; FILE.pfm writes only the PFM; nothing else\n"
          "                          (default out/<scene>.png). sequence: -o DIR, the frames' folder\n"
          "  --hdr FILE.pfm          linear HDR output beside a PNG (default: the PNG path, .pfm)\n"
          "  --size WxH              image size (default 640x480)\n"
          "  --threads N             worker threads incl. the main one (default: cores)\n"
          "  --isa auto|sse2|sse4.2|avx2|avx512\n"
          "                          pin Embree's and softgi's SIMD ISA (default auto)\n"
          "  --exposure STOPS        PNG exposure, 2^STOPS before Reinhard (default 0)\n"
          "  --camera ex,ey,ez:tx,ty,tz:fovy_deg\n"
          "  --light point:x,y,z:r,g,b:I           (I: W/sr)\n"
          "  --light spot:x,y,z:dx,dy,dz:inner_deg,outer_deg:r,g,b:I\n"
          "  --light dir:dx,dy,dz:r,g,b:E           (E: W/m^2)\n"
          "                          lights given replace the scene's lights\n"
          "  --shadow-size N         direct-light shadow map resolution (default 1024)\n"
          "  --max-memory SIZE       memory budget, e.g. 8G or 512M (default: half of this\n"
          "                          machine's memory); larger scenes and frames are refused\n"
          "  --area-strata N         area lights, ray-traced direct light: N x N stratified\n"
          "                          samples per pixel (1..16, default 4)\n"
          "  --area-points K         area lights, rasterized direct light: K emitter points,\n"
          "                          each with a paraboloid shadow map (1..1024, default 32)\n"
          "  --indirect-only, --direct-only\n"
          "  --vpls N                VPL budget (default 256)\n"
          "  --method NAME           VPL method (default ir): ir, iir, smc, mir, invtm, tcas, ssvp\n"
          "  --bounces B             light bounces for VPLs / reference paths (default 3)\n"
          "  --tiles NxM             interleaved tiles (default 4x4)\n"
          "  --no-interleave         every pixel sees every VPL\n"
          "  --clamp C               bounded geometry term b = C / diagonal^2 (default 400, 0 = off)\n"
          "  --filter box|bilateral|gaussian|none  indirect-light filter (default box, Laine 2007 Fig. 5;\n"
          "                        gaussian: Aranha SSVP Sec. III-D edge-aware Gaussian)\n"
          "  --visibility paraboloid|ism|raytrace  VPL visibility (default exact paraboloid maps)\n"
          "  --ism-res N             --visibility ism: texels per ISM side, a power of two 8..512 (default 64)\n"
          "  --ism-points N          --visibility ism: points splatted per frame (default 1000000)\n"
          "  --ism-bias S            --visibility ism: bias, x the exact maps' bias, 1..64 (default 2)\n"
          "  --param KEY=VALUE       a parameter of the VPL method (repeatable; see README)\n"
          "  --dump-stages DIR       write every stage's buffer as an image\n"
          "  --pipeline on|off       overlap the next frame's VPL update with this frame\n"
          "                          (one frame of VPL delay; default off; bench frame: both)\n"
          "  --spp N                 reference: samples per pixel (default 64)\n"
          "  --reference             sequence: path-trace every frame (the references evaluate uses)\n"
          "  --track-spp N           sequence --reference: the tracked pixels with N samples\n"
          "  --reuse-frames          sequence --reference --track-spp: keep the folder's frames, redo\n"
          "                          only the tracked pixels\n"
          "  --raytrace              Embree primary rays and shadow rays (the reference\n"
          "                          path) instead of the rasterized G-buffer and shadow maps\n"
          "  --hash                  print a 64-bit hash of the linear output and the ISA used\n"
          "                          (the same on every ISA and processor)\n"
          "  -q, --quiet             no timing table\n"
          "  --frames N              bench: repetitions per measurement (default 15)\n"
          "                          view: render N frames, then exit (after --screenshot)\n"
          "  --screenshot FILE.png   view: save the window (without the HUD) after --frames N (default 1)\n"
          "  --scenes DIR            bench: folder with sibenik/ and conference/ (default ../shared/scenes)\n"
          "  --moving-light          bench frame: the light moves on a small circle every frame\n"
          "  -h, --help, --version\n",
          out);
}

/* Parses exactly one finite float from [s, s+len). */
static int pf__float(const char *s, size_t len, float *out)
{
    char buf[64];
    if (len == 0 || len >= sizeof buf) return 0;
    memcpy(buf, s, len);
    buf[len] = 0;
    char *end;
    errno = 0;
    float v = strtof(buf, &end);
    if (*end != 0 || errno == ERANGE || !isfinite(v)) return 0;
    *out = v;
    return 1;
}

/* Splits `s` at `sep` into up to `max` fields; returns the field count. */
static int pf__split(const char *s, char sep, const char **start, size_t *len, int max)
{
    int n = 0;
    const char *p = s;
    for (;;) {
        const char *q = strchr(p, sep);
        if (n == max) return max + 1;
        start[n] = p;
        len[n] = q ? (size_t)(q - p) : strlen(p);
        n++;
        if (!q) return n;
        p = q + 1;
    }
}

/* Parses "a,b,c" (exactly `count` floats) from a field. */
static int pf__floats(const char *s, size_t len, float *out, int count)
{
    char buf[256];
    if (len >= sizeof buf) return 0;
    memcpy(buf, s, len);
    buf[len] = 0;
    const char *st[8];
    size_t ln[8];
    if (pf__split(buf, ',', st, ln, 8) != count) return 0;
    for (int i = 0; i < count; i++)
        if (!pf__float(st[i], ln[i], &out[i])) return 0;
    return 1;
}

pf_result pf_cli_parse_camera(const char *spec, pf_vec3 *eye, pf_vec3 *target, float *fovy, pf_error *err)
{
    const char *st[4];
    size_t ln[4];
    float e[3], t[3];
    if (pf__split(spec, ':', st, ln, 3) != 3 || !pf__floats(st[0], ln[0], e, 3) ||
        !pf__floats(st[1], ln[1], t, 3) || !pf__float(st[2], ln[2], fovy))
        return pf_error_set(err, PF_ERR_ARGUMENT, "--camera '%s': expected ex,ey,ez:tx,ty,tz:fovy_deg", spec);
    *eye = pf_v3(e[0], e[1], e[2]);
    *target = pf_v3(t[0], t[1], t[2]);
    /* as scene coordinates: beyond, target - eye overflows and shading is meaningless */
    if (!pf_scene_coord_ok(*eye) || !pf_scene_coord_ok(*target))
        return pf_error_set(err, PF_ERR_ARGUMENT, "--camera '%s': coordinates must lie within +-%g", spec,
                                (double)PF_SCENE_MAX_COORD);
    if (!(*fovy > 0.0f && *fovy < 180.0f))
        return pf_error_set(err, PF_ERR_ARGUMENT, "--camera '%s': fovy must be in (0, 180) degrees", spec);
    if (e[0] == t[0] && e[1] == t[1] && e[2] == t[2])
        return pf_error_set(err, PF_ERR_ARGUMENT, "--camera '%s': eye and target must differ", spec);
    return PF_OK;
}

static pf_result pf__colour_intensity(const char *spec, const char *cs, size_t cl, const char *is, size_t il,
                                      pf_light *out, pf_error *err)
{
    float c[3];
    if (!pf__floats(cs, cl, c, 3) || !pf__float(is, il, &out->intensity))
        return pf_error_set(err, PF_ERR_ARGUMENT, "--light '%s': bad colour r,g,b or intensity", spec);
    if (c[0] < 0 || c[1] < 0 || c[2] < 0 || out->intensity < 0)
        return pf_error_set(err, PF_ERR_ARGUMENT, "--light '%s': colour and intensity must be >= 0", spec);
    double cmax = fmax(c[0], fmax(c[1], c[2]));
    if (cmax * out->intensity > PF_MAX_RADIANCE)
        return pf_error_set(err, PF_ERR_ARGUMENT, "--light '%s': intensity x colour must be at most %g", spec,
                            (double)PF_MAX_RADIANCE);
    out->color = pf_v3(c[0], c[1], c[2]);
    return PF_OK;
}

static pf_result pf__direction(const char *spec, const char *s, size_t l, pf_vec3 *out, pf_error *err)
{
    float d[3];
    if (!pf__floats(s, l, d, 3))
        return pf_error_set(err, PF_ERR_ARGUMENT, "--light '%s': bad direction dx,dy,dz", spec);
    /* normalised in double: (1e38, 1e38, 0) overflows a float length */
    double len = sqrt((double)d[0] * d[0] + (double)d[1] * d[1] + (double)d[2] * d[2]);
    if (!(len > 0.0) || !isfinite(len))
        return pf_error_set(err, PF_ERR_ARGUMENT, "--light '%s': direction must not be zero", spec);
    *out = pf_v3((float)(d[0] / len), (float)(d[1] / len), (float)(d[2] / len));
    return PF_OK;
}

pf_result pf_cli_parse_light(const char *spec, pf_light *out, pf_error *err)
{
    memset(out, 0, sizeof *out);
    const char *st[8];
    size_t ln[8];
    int n = pf__split(spec, ':', st, ln, 7);
    float v[3];
    pf_result r;
    if (n >= 1 && ln[0] == 5 && strncmp(st[0], "point", 5) == 0) {
        if (n != 4 || !pf__floats(st[1], ln[1], v, 3))
            return pf_error_set(err, PF_ERR_ARGUMENT, "--light '%s': expected point:x,y,z:r,g,b:I", spec);
        out->type = PF_LIGHT_POINT;
        out->position = pf_v3(v[0], v[1], v[2]);
        if (!pf_scene_coord_ok(out->position))
            return pf_error_set(err, PF_ERR_ARGUMENT, "--light '%s': position must lie within +-%g", spec,
                                (double)PF_SCENE_MAX_COORD);
        snprintf(out->name, sizeof out->name, "cli-point");
        return pf__colour_intensity(spec, st[2], ln[2], st[3], ln[3], out, err);
    }
    if (n >= 1 && ln[0] == 4 && strncmp(st[0], "spot", 4) == 0) {
        float cone[2];
        if (n != 6 || !pf__floats(st[1], ln[1], v, 3) || !pf__floats(st[3], ln[3], cone, 2))
            return pf_error_set(err, PF_ERR_ARGUMENT,
                                "--light '%s': expected spot:x,y,z:dx,dy,dz:inner_deg,outer_deg:r,g,b:I", spec);
        out->type = PF_LIGHT_SPOT;
        out->position = pf_v3(v[0], v[1], v[2]);
        if (!pf_scene_coord_ok(out->position))
            return pf_error_set(err, PF_ERR_ARGUMENT, "--light '%s': position must lie within +-%g", spec,
                                (double)PF_SCENE_MAX_COORD);
        if ((r = pf__direction(spec, st[2], ln[2], &out->direction, err)) != PF_OK) return r;
        if (!(cone[0] >= 0.0f && cone[0] < cone[1] && cone[1] <= 90.0f))
            return pf_error_set(err, PF_ERR_ARGUMENT, "--light '%s': need 0 <= inner < outer <= 90 degrees", spec);
        out->inner_cone = pf_radians(cone[0]);
        out->outer_cone = pf_radians(cone[1]);
        snprintf(out->name, sizeof out->name, "cli-spot");
        return pf__colour_intensity(spec, st[4], ln[4], st[5], ln[5], out, err);
    }
    if (n >= 1 && ln[0] == 3 && strncmp(st[0], "dir", 3) == 0) {
        if (n != 4) return pf_error_set(err, PF_ERR_ARGUMENT, "--light '%s': expected dir:dx,dy,dz:r,g,b:E", spec);
        out->type = PF_LIGHT_DIRECTIONAL;
        if ((r = pf__direction(spec, st[1], ln[1], &out->direction, err)) != PF_OK) return r;
        snprintf(out->name, sizeof out->name, "cli-dir");
        return pf__colour_intensity(spec, st[2], ln[2], st[3], ln[3], out, err);
    }
    return pf_error_set(err, PF_ERR_ARGUMENT, "--light '%s': type must be point, spot or dir", spec);
}

static pf_result pf__uint(const char *opt, const char *s, uint32_t lo, uint32_t hi, uint32_t *out, pf_error *err)
{
    char *end;
    errno = 0;
    unsigned long v = strtoul(s, &end, 10);
    if (*s < '0' || *s > '9' || *end != 0 || errno == ERANGE || v < lo || v > hi)
        return pf_error_set(err, PF_ERR_ARGUMENT, "%s '%s': expected an integer in %u..%u", opt, s, lo, hi);
    *out = (uint32_t)v;
    return PF_OK;
}

pf_result pf_cli_parse(pf_options *o, int argc, char **argv, pf_error *err)
{
    memset(o, 0, sizeof *o);
    o->pipeline = -1;
    pf_result r = PF_OK;
    for (int i = 1; i < argc && r == PF_OK; i++) {
        const char *a = argv[i];
        /* options that take a value */
        const char *val = NULL;
        static const char *const with_value[] = {"-o",       "--output", "--hdr",      "--size",
                                                 "--threads", "--isa",   "--camera",   "--light",
                                                 "--exposure", "--frames", "--scenes", "--shadow-size", "--area-strata", "--area-points",
                                                 "--vpls",     "--tiles",  "--clamp",  "--method",
                                                 "--bounces",  "--filter", "--visibility", "--dump-stages",
                                                 "--spp",      "--param",  "--screenshot", "--pipeline", "--track-spp",
                                                 "--ism-res",  "--ism-points", "--ism-bias", "--max-memory"};
        for (size_t k = 0; k < sizeof with_value / sizeof with_value[0]; k++)
            if (strcmp(a, with_value[k]) == 0) {
                if (i + 1 >= argc) return pf_error_set(err, PF_ERR_ARGUMENT, "%s needs a value", a);
                val = argv[++i];
            }
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) o->help = 1;
        else if (!strcmp(a, "--version")) o->version = 1;
        else if (!strcmp(a, "--hash")) o->print_hash = 1;
        else if (!strcmp(a, "--raytrace")) o->raytrace = 1;
        else if (!strcmp(a, "--reference")) o->reference = 1;
        else if (!strcmp(a, "--reuse-frames")) o->reuse_frames = 1;
        else if (!strcmp(a, "--moving-light")) o->moving_light = 1;
        else if (!strcmp(a, "-q") || !strcmp(a, "--quiet")) o->quiet = 1;
        else if (!strcmp(a, "-o") || !strcmp(a, "--output")) o->out_path = val;
        else if (!strcmp(a, "--hdr")) o->hdr_path = val;
        else if (!strcmp(a, "--threads")) r = pf__uint(a, val, 1, 256, &o->threads, err);
        else if (!strcmp(a, "--frames")) r = pf__uint(a, val, 1, 1000, &o->frames, err);
        else if (!strcmp(a, "--shadow-size")) r = pf__uint(a, val, 16, 8192, &o->shadow_size, err);
        else if (!strcmp(a, "--max-memory")) r = pf_budget_parse(val, &o->max_memory, err);
        else if (!strcmp(a, "--area-strata")) r = pf__uint(a, val, 1, 16, &o->area_strata, err);
        else if (!strcmp(a, "--area-points")) r = pf__uint(a, val, 1, 1024, &o->area_points, err);
        else if (!strcmp(a, "--indirect-only")) o->indirect_only = 1;
        else if (!strcmp(a, "--direct-only")) o->direct_only = 1;
        else if (!strcmp(a, "--no-interleave")) o->no_interleave = 1;
        else if (!strcmp(a, "--vpls")) r = pf__uint(a, val, 1, 1u << 20, &o->vpls, err);
        else if (!strcmp(a, "--bounces")) r = pf__uint(a, val, 1, 64, &o->bounces, err);
        else if (!strcmp(a, "--spp")) r = pf__uint(a, val, 1, 1u << 20, &o->spp, err);
        else if (!strcmp(a, "--track-spp")) r = pf__uint(a, val, 1, 1u << 24, &o->track_spp, err);
        else if (!strcmp(a, "--method")) o->method = val;
        else if (!strcmp(a, "--param")) {
            if (o->param_count >= 32) r = pf_error_set(err, PF_ERR_ARGUMENT, "--param: at most 32 parameters");
            else if (!strchr(val, '=') || val[0] == '=')
                r = pf_error_set(err, PF_ERR_ARGUMENT, "--param '%s': expected KEY=VALUE", val);
            else o->params[o->param_count++] = val;
        }
        else if (!strcmp(a, "--ism-res")) {
            r = pf__uint(a, val, 8, 512, &o->ism_res, err);
            if (r == PF_OK && (o->ism_res & (o->ism_res - 1)))
                r = pf_error_set(err, PF_ERR_ARGUMENT, "--ism-res '%s': expected a power of two in 8..512", val);
        } else if (!strcmp(a, "--ism-points")) r = pf__uint(a, val, 1000, 100000000, &o->ism_points, err);
        else if (!strcmp(a, "--ism-bias")) {
            if (!pf__float(val, strlen(val), &o->ism_bias) || !(o->ism_bias >= 1.0f && o->ism_bias <= 64.0f))
                r = pf_error_set(err, PF_ERR_ARGUMENT, "--ism-bias '%s': expected a number in 1..64", val);
        }
        else if (!strcmp(a, "--dump-stages")) o->dump_dir = val;
        else if (!strcmp(a, "--screenshot")) {
            size_t n = strlen(val);
            o->screenshot_path = val;
            if (n < 5 || strcasecmp(val + n - 4, ".png") != 0)
                r = pf_error_set(err, PF_ERR_ARGUMENT, "--screenshot '%.200s': the screenshot is a PNG (name it .png)",
                                 val);
        }
        else if (!strcmp(a, "--pipeline")) {
            if (!strcmp(val, "on")) o->pipeline = 1;
            else if (!strcmp(val, "off")) o->pipeline = 0;
            else r = pf_error_set(err, PF_ERR_ARGUMENT, "--pipeline '%s': expected on or off", val);
        }
        else if (!strcmp(a, "--filter")) {
            o->filter = val;
            if (strcmp(val, "box") && strcmp(val, "bilateral") && strcmp(val, "gaussian") && strcmp(val, "none"))
                r = pf_error_set(err, PF_ERR_ARGUMENT, "--filter '%s': expected box, bilateral, gaussian or none", val);
        } else if (!strcmp(a, "--visibility")) {
            if (!strcmp(val, "raytrace")) o->visibility_raytrace = 1;
            else if (!strcmp(val, "ism")) o->visibility_ism = 1;
            else if (strcmp(val, "paraboloid"))
                r = pf_error_set(err, PF_ERR_ARGUMENT, "--visibility '%s': expected paraboloid, ism or raytrace", val);
        } else if (!strcmp(a, "--clamp")) {
            if (!pf__float(val, strlen(val), &o->clamp) || o->clamp < 0.0f)
                r = pf_error_set(err, PF_ERR_ARGUMENT, "--clamp '%s': expected a number >= 0 (0 = off)", val);
            o->clamp_set = 1;
        } else if (!strcmp(a, "--tiles")) {
            const char *x = strchr(val, 'x');
            char nbuf[16];
            if (!x || (size_t)(x - val) >= sizeof nbuf)
                r = pf_error_set(err, PF_ERR_ARGUMENT, "--tiles '%s': expected NxM, e.g. 4x4", val);
            else {
                memcpy(nbuf, val, (size_t)(x - val));
                nbuf[x - val] = 0;
                r = pf__uint("--tiles n", nbuf, 1, 16, &o->tiles_n, err);
                if (r == PF_OK) r = pf__uint("--tiles m", x + 1, 1, 16, &o->tiles_m, err);
            }
        }
        else if (!strcmp(a, "--scenes")) o->scenes_dir = val;
        else if (!strcmp(a, "--isa")) r = pf_isa_parse(val, &o->isa, err);
        else if (!strcmp(a, "--exposure")) {
            if (!pf__float(val, strlen(val), &o->exposure) || fabsf(o->exposure) > 64.0f)
                r = pf_error_set(err, PF_ERR_ARGUMENT, "--exposure '%s': expected a number of stops in -64..64", val);
        } else if (!strcmp(a, "--size")) {
            const char *x = strchr(val, 'x');
            char wbuf[16];
            if (!x || (size_t)(x - val) >= sizeof wbuf)
                r = pf_error_set(err, PF_ERR_ARGUMENT, "--size '%s': expected WxH, e.g. 640x480", val);
            else {
                memcpy(wbuf, val, (size_t)(x - val));
                wbuf[x - val] = 0;
                r = pf__uint("--size width", wbuf, 1, 16384, &o->width, err);
                if (r == PF_OK) r = pf__uint("--size height", x + 1, 1, 16384, &o->height, err);
                /* a frame keeps ~130 bytes a pixel (G-buffer, split buffers, irradiance): 8 GiB here */
                if (r == PF_OK && (uint64_t)o->width * o->height > (uint64_t)1 << 26)
                    r = pf_error_set(err, PF_ERR_ARGUMENT,
                                     "--size %ux%u: at most 67108864 pixels (e.g. 8192x8192)", o->width, o->height);
            }
        } else if (!strcmp(a, "--camera")) {
            r = pf_cli_parse_camera(val, &o->camera_eye, &o->camera_target, &o->camera_fovy_deg, err);
            o->has_camera = 1;
        } else if (!strcmp(a, "--light")) {
            if (o->light_count == PF_CLI_MAX_LIGHTS)
                r = pf_error_set(err, PF_ERR_ARGUMENT, "at most %d --light options", PF_CLI_MAX_LIGHTS);
            else
                r = pf_cli_parse_light(val, &o->lights[o->light_count++], err);
        } else if (a[0] == '-' && a[1] != 0)
            r = pf_error_set(err, PF_ERR_ARGUMENT, "unknown option '%s' (see softgi --help)", a);
        else if (!o->command)
            o->command = a;
        else if (!o->scene_path)
            o->scene_path = a;
        else
            r = pf_error_set(err, PF_ERR_ARGUMENT, "unexpected argument '%s'", a);
    }
    if (r != PF_OK) return r;
    if (!o->help && !o->version) {
        if (!o->command) return pf_error_set(err, PF_ERR_ARGUMENT, "no command given (see softgi --help)");
        if (strcmp(o->command, "render") != 0 && strcmp(o->command, "bench") != 0 &&
            strcmp(o->command, "reference") != 0 && strcmp(o->command, "sequence") != 0 &&
            strcmp(o->command, "view") != 0)
            return pf_error_set(err, PF_ERR_ARGUMENT,
                                "unknown command '%s' (softgi knows: render, view, reference, sequence, bench, "
                                "compare, evaluate)",
                                o->command);
        if (o->reuse_frames && !o->track_spp)
            return pf_error_set(err, PF_ERR_ARGUMENT, "--reuse-frames: only with sequence --reference --track-spp");
        if (o->track_spp && !o->reference)
            return pf_error_set(err, PF_ERR_ARGUMENT, "--track-spp: only with sequence --reference");
        if (o->reference && strcmp(o->command, "sequence") != 0)
            return pf_error_set(err, PF_ERR_ARGUMENT, "--reference is an option of sequence (softgi reference renders "
                                                      "one image)");
        if (!strcmp(o->command, "sequence") && !o->scene_path)
            return pf_error_set(err, PF_ERR_ARGUMENT, "sequence: give the sequence file (softgi sequence FILE.json)");
        if (o->moving_light && (strcmp(o->command, "bench") != 0 || !o->scene_path || strcmp(o->scene_path, "frame")))
            return pf_error_set(err, PF_ERR_ARGUMENT, "--moving-light: only bench frame takes it");
        if (o->indirect_only && o->direct_only)
            return pf_error_set(err, PF_ERR_ARGUMENT, "--indirect-only and --direct-only exclude each other");
        if (!strcmp(o->command, "bench") &&
            (!o->scene_path || (strcmp(o->scene_path, "raster") != 0 && strcmp(o->scene_path, "frame") != 0)))
            return pf_error_set(err, PF_ERR_ARGUMENT, "bench '%s': softgi can bench: raster, frame",
                                o->scene_path ? o->scene_path : "");
    }
    return PF_OK;
}
