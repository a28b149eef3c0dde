/* app_evaluate: `softgi evaluate`, Hedman 2017 Table 1 (and Fig. 7) on our
 * sequences: every VPL method against per-frame path-traced references.
 *
 *   softgi evaluate [--methods LIST] [--sequences FILE,FILE,...] [--out DIR]
 *                   [--size WxH] [--spp N] [--vpls N] [--threads N]
 *                   [--full] [--rerun-reference] [--param KEY=VALUE ...] [-q]
 *                   [--frames A:B]
 *
 * For each sequence file (default: eight in scenes/sequences: the McGuire
 * Cornell box, Sibenik and the conference room, each with a moving camera and
 * a moving light, and the anim-box room with a moving object (anim-move)
 * and with a deforming one (anim-deform)):
 *   1. the reference: `softgi sequence FILE --reference --spp N --track-spp T`
 *      (the tracked pixels, where |E| and |E'| are measured, with T samples, so
 *      the reference's own noise stays out of |E'|) into
 *      OUT/NAME/reference (kept and reused while OUT/NAME/reference/stamp
 *      records the same size, spp and image kind and its frames.txt says the
 *      run finished; --rerun-reference forces it);
 *   2. every method: `softgi sequence FILE --method M --vpls N` into
 *      OUT/NAME/M (the method keeps its state over the frames, as in an
 *      interactive session); a method that fails (e.g. one not implemented)
 *      is reported in the table and skipped. An entry METHOD+KEY=VALUE...
 *      gives that method parameters of its own (its folder and row are
 *      named by the whole entry): the default list has IR twice, as
 *      `ir` (a static light keeps its VPLs) and `ir+reseed=1` (new VPLs
 *      every frame, the IR the papers compare with). A method whose frames
 *      hold no indirect light at all (it found no light it can use, e.g.
 *      a reflective-shadow-map method on a scene lit only by emissive
 *      triangles) gets a row of n/a with the reason, never numbers;
 *   3. `softgi compare --reference OUT/NAME/reference --name M:OUT/NAME/M ...
 *      --track (the sequence's tracked pixels) --table OUT/NAME/table.md
 *      --plot OUT/NAME/plot.svg`: |E|, |E'| (Eq. 10), TID and RMSE.
 * The tables of all sequences are gathered in OUT/table.md.
 * Every file is written to a temporary file and renamed into place when
 * complete (pf_imageio.h): OUT/table.md is built in memory and written at
 * the end (a probe at the start checks that OUT accepts new files), the
 * reference stamp only after its frames are all written.
 *
 * By default only the indirect light is rendered and compared (--indirect-only
 * for references and methods): the direct light is the same shadow-mapped
 * term for every method, so leaving it in would only add the same error to
 * each. --full compares the whole images instead.
 *
 * --frames A:B: only the references' frames A..B-1 of
 * every sequence (zero-based, B excluded, clipped to each sequence's
 * length; a sequence that ends before A is skipped), the one step that
 * outgrows a machine, so that a batch scheduler can spread them: no
 * method runs, no table. Each range writes the files a full reference run
 * writes (the frames under their own names, track.txt, the finished
 * frames.txt and the stamp), so the OUT folders of all ranges merged by
 * file name are a finished evaluation's references, and a final
 * `softgi evaluate` with the same options (without --frames) reuses them
 * and runs the methods. A range whose frames are all present with the
 * same stamp is skipped; a folder whose stamp records other settings is
 * refused (rendering into it would mix two settings) unless
 * --rerun-reference. A reference folder that says it is finished but lacks
 * a frame (a range not merged yet) is refused, with the range to render.
 *
 * Progress (app_progress.h): one bar over the steps (a reference or a
 * method run each), on a terminal and without -q.
 *
 * --quality runs app_quality instead (app_quality.c):
 * the image-quality table of single static frames against a reference and
 * a many-VPL proxy; the sequence options (--sequences, --track-spp,
 * --frames, --full) do not apply to it, and its own (--quality-scenes,
 * --scenes, --proxy-vpls, --table) only to it.
 *
 * Everything runs in this process through the same functions as the
 * commands (app_sequence, app_compare), with argument vectors built here, so
 * the options are validated exactly as on the command line. */
#define _DEFAULT_SOURCE /* realpath */
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "app.h"
#include "app_progress.h"
#include "gi_reference.h"
#include "gi_vpl.h"
#include "pf_imageio.h"
#include "pf_sequence.h"
#include "pf_timer.h"

#define EV_MAX_ITEMS 32
#define EV_MAX_ARGS 96
#define EV_MAX_ENTRY_PARAMS 8

typedef struct ev__args {
    const char *methods[EV_MAX_ITEMS];
    uint32_t method_count;
    const char *sequences[EV_MAX_ITEMS];
    uint32_t sequence_count;
    const char *out;
    const char *size, *spp, *track_spp, *vpls, *threads, *isa;
    const char *params[EV_MAX_ITEMS];
    uint32_t param_count;
    int full, rerun_reference, quiet;
    int quality;                                   /* --quality: app_quality */
    const char *table, *quality_scenes, *scenes_dir, *proxy_vpls; /* its options */
    const char *given_seq_option;                  /* a sequence-only option given, as spelt */
    const char *given_quality_option;              /* a --quality-only option given */
    app_progress *bar;               /* the steps' bar (ev__run's) */
    uint32_t steps_done, steps_total;
    int ranged;                      /* --frames A:B */
    uint32_t frame_first, frame_end; /* frame_end PF_CLI_FRAMES_END: open */
    char lists[2][4096]; /* storage for split --methods / --sequences */
    char default_sequences[8][4200];
} ev__args;

static void ev__usage(FILE *f)
{
    fputs("usage: softgi evaluate [--methods LIST] [--sequences FILE,FILE,...] [--out DIR]\n"
          "                       [--size WxH] [--spp N] [--track-spp N] [--vpls N] [--threads N] [--isa NAME]\n"
          "                       [--param KEY=VALUE ...] [--full] [--rerun-reference] [--frames A:B] [-q]\n"
          "       softgi evaluate --quality [--methods LIST] [--quality-scenes LIST] [--scenes DIR]\n"
          "                       [--size WxH] [--spp N] [--vpls N] [--proxy-vpls N] [--out DIR]\n"
          "                       [--table FILE] [--threads N] [--isa NAME] [--param KEY=VALUE ...]\n"
          "                       [--rerun-reference] [-q]\n"
          "\n"
          "Hedman et al. 2017, Table 1 on softgi's sequences: for each sequence, per-frame\n"
          "path-traced references (softgi sequence --reference), every method's frames\n"
          "(softgi sequence --method M), and softgi compare's |E|, |E'|, TID and RMSE table\n"
          "and Fig. 7-style plot. Writes OUT/NAME/{reference,METHOD}/frame_NNNN.*,\n"
          "OUT/NAME/table.md, OUT/NAME/plot.svg and OUT/table.md.\n"
          "\n"
          "  --methods LIST      comma-separated VPL methods, each optionally with parameters of\n"
          "                      its own as METHOD+KEY=VALUE+... (default: ir, ir+reseed=1, iir,\n"
          "                      smc, mir, invtm, tcas, ssvp)\n"
          "  --sequences LIST    comma-separated .seq.json files (default: scenes/sequences/\n"
          "                      cornell-{camera,light}, sibenik-{camera,light},\n"
          "                      conference-{camera,light}, anim-move, anim-deform)\n"
          "  --out DIR           output folder (default out/evaluate)\n"
          "  --size WxH          image size for every sequence (default 320x240)\n"
          "  --spp N             reference samples per pixel (default 256)\n"
          "  --track-spp N       reference samples at the tracked pixels, where |E| and |E'| are\n"
          "                      measured (default 4096)\n"
          "  --vpls N            VPL budget of every method (default 256)\n"
          "  --param KEY=VALUE   passed to every method that knows KEY (repeatable)\n"
          "  --full              compare whole images (default: indirect light only)\n"
          "  --rerun-reference   render the references even when a matching one exists\n"
          "  --frames A:B        only the references' frames A..B-1 of every sequence (zero-based,\n"
          "                      B excluded, clipped to each sequence; A: to the end; N: frame N), for a\n"
          "                      batch scheduler: merge the OUT folders of all ranges, then run evaluate\n"
          "                      again without --frames for the methods and tables\n"
          "  -q, --quiet         no progress lines or bar\n"
          "\n"
          "--quality: one static frame per method and scene at seven settings (paper: the\n"
          "paper defaults; softgi: --compensate on; temporal: also --temporal 16, frame 15;\n"
          "atrous, atrous+temporal: --filter atrous; cycle, cycle32: --vpl-cycle 16 / 32),\n"
          "indirect light only, against a path-traced reference and a proxy (IR, every VPL at every\n"
          "pixel, no clamp, no filter) with the method's bounce count: mean relative error per\n"
          "pixel, energy ratio and frame time as a Markdown table in OUT/quality.md. References and\n"
          "proxies are kept in OUT/quality/SCENE and reused while their stamp matches.\n"
          "  --quality           the quality table instead of the sequences (default methods: ir,\n"
          "                      ir+reseed=1, iir, smc, mir, invtm, tcas, ssvp, ssvp+origin=members;\n"
          "                      --size: each scene's own; --spp 4096)\n"
          "  --quality-scenes LIST  cornell (embedded, 320x240), sibenik (256x192), conference\n"
          "                      (256x192) (default cornell,sibenik)\n"
          "  --scenes DIR        the shared scenes' folder (default: ../shared/scenes beside the source)\n"
          "  --proxy-vpls N      the proxy's VPLs (default 16384)\n"
          "  --table FILE        write the table to FILE too (docs/evaluation/quality.md)\n",
          f);
}

static int ev__fail(int code, const char *fmt, const char *a, const char *b)
{
    fprintf(stderr, "softgi: evaluate: ");
    fprintf(stderr, fmt, a, b);
    fprintf(stderr, "\n");
    return code;
}

/* Splits a comma-separated list into items (in place in `store`). */
static int ev__split(const char *list, char *store, size_t store_size, const char **items, uint32_t *count,
                     const char *what)
{
    if (strlen(list) >= store_size) return ev__fail(2, "--%s: the list is too long%s", what, "");
    strcpy(store, list);
    *count = 0;
    for (char *p = store; p;) {
        char *c = strchr(p, ',');
        if (c) *c = 0;
        if (!*p) return ev__fail(2, "--%s '%s': empty item", what, list);
        if (*count == EV_MAX_ITEMS) return ev__fail(2, "--%s: at most 32 items%s", what, "");
        items[(*count)++] = p;
        p = c ? c + 1 : NULL;
    }
    return 0;
}

/* A --methods entry METHOD+KEY=VALUE+...: the method's name. */
static void ev__method_name(const char *entry, char *out, size_t size)
{
    snprintf(out, size, "%.*s", (int)strcspn(entry, "+"), entry);
}

static int ev__parse(ev__args *a, int argc, char **argv, int *help)
{
    memset(a, 0, sizeof *a);
    a->out = "out/evaluate";
    for (int i = 2; i < argc; i++) {
        const char *o = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(o, "-h") || !strcmp(o, "--help")) {
            *help = 1;
            return 0;
        }
        if (!strcmp(o, "--full")) a->full = 1, a->given_seq_option = o;
        else if (!strcmp(o, "--quality")) a->quality = 1;
        else if (!strcmp(o, "--rerun-reference")) a->rerun_reference = 1;
        else if (!strcmp(o, "-q") || !strcmp(o, "--quiet")) a->quiet = 1;
        else {
            static const char *const with_value[] = {"--methods", "--sequences", "--out",   "--size", "--spp",
                                                     "--vpls",    "--threads",   "--param", "--isa",
                                                     "--track-spp", "--frames", "--table", "--quality-scenes",
                                                     "--scenes", "--proxy-vpls"};
            int known = 0;
            for (size_t k = 0; k < sizeof with_value / sizeof with_value[0]; k++) known |= !strcmp(o, with_value[k]);
            if (!known) return ev__fail(2, "unknown option '%s' (see softgi evaluate --help)%s", o, "");
            if (!v) return ev__fail(2, "%s needs a value%s", o, "");
            i++;
            int rc = 0;
            if (!strcmp(o, "--methods")) {
                rc = ev__split(v, a->lists[0], sizeof a->lists[0], a->methods, &a->method_count, "methods");
                for (uint32_t k = 0; !rc && k < a->method_count; k++) {
                    char name[64];
                    ev__method_name(a->methods[k], name, sizeof name);
                    if (!gi_vpl_method_find(name))
                        rc = ev__fail(2, "--methods: unknown method '%s' (softgi knows %s)", a->methods[k],
                                      gi_vpl_method_names());
                }
            } else if (!strcmp(o, "--sequences")) {
                a->given_seq_option = o;
                rc = ev__split(v, a->lists[1], sizeof a->lists[1], a->sequences, &a->sequence_count, "sequences");
            } else if (!strcmp(o, "--table")) a->table = v, a->given_quality_option = o;
            else if (!strcmp(o, "--quality-scenes")) a->quality_scenes = v, a->given_quality_option = o;
            else if (!strcmp(o, "--scenes")) a->scenes_dir = v, a->given_quality_option = o;
            else if (!strcmp(o, "--proxy-vpls")) a->proxy_vpls = v, a->given_quality_option = o;
            else if (!strcmp(o, "--out")) a->out = v;
            else if (!strcmp(o, "--size")) a->size = v;
            else if (!strcmp(o, "--spp")) a->spp = v;
            else if (!strcmp(o, "--track-spp")) a->track_spp = v, a->given_seq_option = o;
            else if (!strcmp(o, "--vpls")) a->vpls = v;
            else if (!strcmp(o, "--threads")) a->threads = v;
            else if (!strcmp(o, "--isa")) a->isa = v;
            else if (!strcmp(o, "--frames")) {
                pf_error err;
                a->given_seq_option = o;
                a->ranged = 1;
                if (pf_cli_parse_frame_range("--frames", v, &a->frame_first, &a->frame_end, &err) != PF_OK)
                    rc = ev__fail(2, "%s%s", err.message, "");
            }
            else {
                if (a->param_count == EV_MAX_ITEMS) return ev__fail(2, "--param: at most 32%s%s", "", "");
                a->params[a->param_count++] = v;
            }
            if (rc) return rc;
        }
    }
    if (strlen(a->out) > 2000) return ev__fail(2, "--out: the folder name is too long%s%s", "", "");
    if (a->quality && a->given_seq_option)
        return ev__fail(2, "%s does not apply to --quality (it is an option of the sequences' evaluation)%s",
                        a->given_seq_option, "");
    if (!a->quality && a->given_quality_option)
        return ev__fail(2, "%s: only with --quality%s", a->given_quality_option, "");
    if (a->quality) return 0; /* app_quality has its own defaults */
    if (!a->size) a->size = "320x240";
    if (!a->spp) a->spp = "256";
    if (!a->track_spp) a->track_spp = "4096";
    if (!a->vpls) a->vpls = "256";
    if (!a->method_count) {
        static const char *const all[] = {"ir", "ir+reseed=1", "iir", "smc", "mir", "invtm", "tcas", "ssvp"};
        for (size_t k = 0; k < sizeof all / sizeof all[0]; k++) a->methods[a->method_count++] = all[k];
    }
    if (!a->sequence_count) {
        static const char *const names[] = {"cornell-camera",   "cornell-light",    "sibenik-camera",
                                            "sibenik-light",    "conference-camera", "conference-light",
                                            "anim-move",        "anim-deform"};
        for (size_t k = 0; k < sizeof names / sizeof names[0]; k++) {
            snprintf(a->default_sequences[k], sizeof a->default_sequences[k], "%s/scenes/sequences/%s.seq.json",
                     SOFTGI_SOURCE_DIR, names[k]);
            a->sequences[a->sequence_count++] = a->default_sequences[k];
        }
    }
    return 0;
}

/* The sequence's name: its file name without .seq.json / .json. */
static void ev__sequence_name(const char *file, char *out, size_t size)
{
    const char *base = strrchr(file, '/');
    snprintf(out, size, "%s", base ? base + 1 : file);
    char *dot = strstr(out, ".seq.json");
    if (!dot) dot = strstr(out, ".json");
    if (dot) *dot = 0;
}

/* argv builder: the strings must outlive the call they are passed to. */
typedef struct ev__argv {
    int argc;
    char *argv[EV_MAX_ARGS + 1];
} ev__argv;

static void ev__push(ev__argv *v, const char *s)
{
    if (v->argc < EV_MAX_ARGS) v->argv[v->argc++] = (char *)s;
    v->argv[v->argc] = NULL;
}

/* The options every `sequence` run shares. */
static void ev__common(ev__argv *v, const ev__args *a, const char *file, const char *dir)
{
    ev__push(v, "softgi");
    ev__push(v, "sequence");
    ev__push(v, file);
    ev__push(v, "-o");
    ev__push(v, dir);
    ev__push(v, "--size");
    ev__push(v, a->size);
    ev__push(v, "-q");
    if (!a->full) ev__push(v, "--indirect-only");
    if (a->threads) {
        ev__push(v, "--threads");
        ev__push(v, a->threads);
    }
    if (a->isa) {
        ev__push(v, "--isa");
        ev__push(v, a->isa);
    }
}

static int ev__run_sequence(ev__argv *v)
{
    pf_options o;
    pf_error err;
    pf_result r = pf_cli_parse(&o, v->argc, v->argv, &err);
    if (r != PF_OK) {
        fprintf(stderr, "softgi: evaluate: %s\n", err.message);
        return pf_result_exit_code(r);
    }
    return app_sequence(&o);
}

/* Appends the lines of `path` to `out` (a missing file appends nothing). */
static void ev__append_file(FILE *out, const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) return;
    char buf[4096];
    size_t n;
    while ((n = fread(buf, 1, sizeof buf, f)) > 0) fwrite(buf, 1, n, out);
    fclose(f);
}

static int ev__read_text(const char *path, char *buf, size_t size)
{
    FILE *f = fopen(path, "rb");
    if (!f) return 0;
    size_t n = fread(buf, 1, size - 1, f);
    buf[n] = 0;
    fclose(f);
    return 1;
}

/* Progress over the steps (a reference or a method run each):
 * app_progress.h. Clears the bar before a line of text. */
static void ev__progress_clear(const ev__args *a)
{
    if (a->bar) app_progress_clear(a->bar);
}

/* The bar at the start of step `step` of sequence `seq`. */
static void ev__progress(const ev__args *a, const char *seq, const char *step)
{
    char what[320];
    snprintf(what, sizeof what, "step %u/%u: %s: %s", a->steps_done + 1, a->steps_total, seq, step);
    if (a->bar) app_progress_update(a->bar, a->steps_done, a->steps_total, what);
}

/* Whether frame f of a reference folder is all there: the four files a
 * sequence run writes for it (pf_sequence.h). */
static int ev__frame_present(const char *dir, uint32_t f)
{
    static const char *const ext[] = {".pfm", ".png", ".view", ".depth.pfm"};
    for (size_t k = 0; k < sizeof ext / sizeof ext[0]; k++) {
        char path[2700];
        struct stat st;
        snprintf(path, sizeof path, "%s/frame_%04u%s", dir, f, ext[k]);
        if (stat(path, &st) != 0) return 0;
    }
    return 1;
}

/* The first frame of [first, end) missing from dir, or end. */
static uint32_t ev__first_missing(const char *dir, uint32_t first, uint32_t end)
{
    while (first < end && ev__frame_present(dir, first)) first++;
    return first;
}

/* Step 1: the sequence's per-frame references (reused when the stamp says
 * they were made with the same settings). With --frames only frames
 * [first, end) (the top comment). */
static int ev__reference(const ev__args *a, const char *file, const char *dir, uint32_t first, uint32_t end)
{
    char stamp_path[2600], want[PATH_MAX + 384], have[PATH_MAX + 384], base[PATH_MAX + 256], real[PATH_MAX];
    snprintf(stamp_path, sizeof stamp_path, "%s/stamp", dir);
    /* the file by its absolute path, so a relative and an absolute name of
     * the same sequence match */
    if (realpath(file, real)) file = real;
    snprintf(base, sizeof base, "file=%s size=%s spp=%s %s estimator=%s\n", file, a->size, a->spp,
             a->full ? "full" : "indirect", GI_REFERENCE_ESTIMATOR);
    snprintf(want, sizeof want, "%strack-spp=%s\n", base, a->track_spp);
    int reuse = 0;
    /* a run that did not finish (its manifest says "running") is redone */
    pf_sequence_manifest man;
    int has_manifest = 0;
    pf_error merr;
    int finished = pf_sequence_manifest_read(dir, &man, &has_manifest, &merr) == PF_OK && (!has_manifest || man.complete);
    int have_stamp = ev__read_text(stamp_path, have, sizeof have);
    char range[48] = "";
    if (a->ranged) {
        /* one range of a reference spread over machines: never mix settings */
        if (have_stamp && strcmp(have, want) && !a->rerun_reference)
            return ev__fail(1, "%s holds references made with other settings (its stamp); give another --out, or "
                               "--rerun-reference to replace them%s",
                            dir, "");
        if (have_stamp && !strcmp(have, want) && !a->rerun_reference && ev__first_missing(dir, first, end) == end) {
            ev__progress_clear(a);
            if (!a->quiet) printf("  reference: frames %u..%u already in %s (same settings)\n", first, end - 1, dir);
            return 0;
        }
        snprintf(range, sizeof range, "%u:%u", first, end);
    } else if (!a->rerun_reference && finished && have_stamp) {
        if (!strcmp(have, want)) {
            /* finished, but merged from --frames ranges: all there? */
            uint32_t miss = has_manifest ? ev__first_missing(dir, 0, man.frames) : 0;
            if (has_manifest && miss < man.frames) {
                uint32_t to = miss;
                while (to < man.frames && !ev__frame_present(dir, to)) to++;
                char m[160];
                snprintf(m, sizeof m, "frame_%04u is missing (a --frames range not merged yet?); render it with "
                         "softgi evaluate --frames %u:%u (same options) or give --rerun-reference", miss, miss, to);
                return ev__fail(1, "%s: %s", dir, m);
            }
            ev__progress_clear(a);
            if (!a->quiet) printf("  reference: reusing %s (%s)\n", dir, "same settings");
            return 0;
        }
        /* the same images with other tracked-pixel samples: keep them */
        reuse = !strncmp(have, base, strlen(base));
    }
    ev__argv v = {0};
    ev__common(&v, a, file, dir);
    ev__push(&v, "--reference");
    ev__push(&v, "--spp");
    ev__push(&v, a->spp);
    ev__push(&v, "--track-spp");
    ev__push(&v, a->track_spp);
    if (reuse) ev__push(&v, "--reuse-frames");
    if (range[0]) {
        ev__push(&v, "--frames");
        ev__push(&v, range);
    }
    double t0 = pf_time_now();
    int rc = ev__run_sequence(&v);
    if (rc) return rc;
    pf_error err;
    if (pf_imageio_write_file(stamp_path, want, strlen(want), &err) != PF_OK) return app_fail(&err);
    ev__progress_clear(a);
    if (!a->quiet)
        printf("  reference: %s spp (tracked pixels %s)%s%s%s in %.1f s\n", a->spp, a->track_spp,
               reuse ? ", images reused" : "", range[0] ? ", frames " : "", range, pf_time_now() - t0);
    return 0;
}

/* Step 2: one method's frames. Returns 0 or the exit status. */
static int ev__method(const ev__args *a, const char *file, const char *entry, const char *dir)
{
    ev__argv v = {0};
    char method[64], own[512];
    ev__method_name(entry, method, sizeof method);
    ev__common(&v, a, file, dir);
    ev__push(&v, "--method");
    ev__push(&v, method);
    ev__push(&v, "--vpls");
    ev__push(&v, a->vpls);
    /* the entry's own parameters (METHOD+KEY=VALUE+...) always go to it */
    snprintf(own, sizeof own, "%s", entry + strlen(method));
    uint32_t n_own = 0;
    for (char *p = strtok(own, "+"); p && n_own < EV_MAX_ENTRY_PARAMS; p = strtok(NULL, "+"), n_own++) {
        ev__push(&v, "--param");
        ev__push(&v, p);
    }
    /* --param parameters go only to methods that know them: try each alone first */
    const gi_vpl_method *m = gi_vpl_method_find(method);
    for (uint32_t i = 0; i < a->param_count; i++) {
        gi_params p = {0};
        pf_error err;
        void *state = NULL;
        if (gi_params_add(&p, a->params[i], &err) != PF_OK) return ev__fail(2, "%s%s", err.message, "");
        if (m->create(&state, &p, &err) == PF_OK) {
            m->destroy(state);
            ev__push(&v, "--param");
            ev__push(&v, a->params[i]);
        }
    }
    double t0 = pf_time_now();
    int rc = ev__run_sequence(&v);
    ev__progress_clear(a);
    if (!rc && !a->quiet) printf("  %-12s %.1f s\n", entry, pf_time_now() - t0);
    return rc;
}

/* Whether any frame in dir (a finished indirect-only run) holds indirect
 * light: 1 yes, 0 no, -1 the frames could not be read (then the table
 * keeps its numbers and compare reports the problem). */
static int ev__has_light(const char *dir)
{
    pf_sequence_manifest man;
    pf_error err;
    int present = 0;
    if (pf_sequence_manifest_read(dir, &man, &present, &err) != PF_OK || !present) return -1;
    for (uint32_t i = 0; i < man.frames; i++) {
        char path[2600];
        snprintf(path, sizeof path, "%s/frame_%04u.pfm", dir, i);
        float *rgb = NULL;
        uint32_t w = 0, h = 0;
        if (pf_imageio_read_pfm(path, &rgb, &w, &h, &err) != PF_OK) return -1;
        int lit = 0;
        for (size_t k = 0; k < (size_t)w * h * 3 && !lit; k++) lit = rgb[k] > 0.0f;
        free(rgb);
        if (lit) return 1;
    }
    return 0;
}

/* Step 3: softgi compare over the methods that rendered. */
static int ev__compare(const char *seq_dir, const char *ref_dir, char names[][2600], uint32_t count)
{
    ev__argv v = {0};
    char track_args[64][32];
    char table[2600], plot[2600], track_path[2600];
    snprintf(table, sizeof table, "%s/table.md", seq_dir);
    snprintf(plot, sizeof plot, "%s/plot.svg", seq_dir);
    ev__push(&v, "softgi");
    ev__push(&v, "compare");
    ev__push(&v, "--reference");
    ev__push(&v, ref_dir);
    for (uint32_t i = 0; i < count; i++) {
        ev__push(&v, "--name");
        ev__push(&v, names[i]);
    }
    ev__push(&v, "--table");
    ev__push(&v, table);
    ev__push(&v, "--plot");
    ev__push(&v, plot);
    snprintf(track_path, sizeof track_path, "%s/track.txt", ref_dir);
    FILE *tf = fopen(track_path, "r");
    uint32_t nt = 0;
    if (tf) {
        while (nt < 64 && fgets(track_args[nt], sizeof track_args[nt], tf)) {
            track_args[nt][strcspn(track_args[nt], "\r\n")] = 0;
            if (!track_args[nt][0]) continue;
            ev__push(&v, "--track");
            ev__push(&v, track_args[nt]);
            nt++;
        }
        fclose(tf);
    }
    fflush(stdout);
    return app_compare(v.argc, v.argv);
}

/* Rows for the methods that computed no indirect light: n/a and why,
 * under the sequence's table (same columns as softgi compare's). */
static void ev__unlit_rows(FILE *summary, const char *const *unlit, uint32_t count)
{
    if (!count) return;
    fprintf(summary, "\n| method | frames | mean \\|E\\| | mean \\|E'\\| | TID | RMSE |\n|---|---:|---:|---:|---:|---:|\n");
    for (uint32_t i = 0; i < count; i++) fprintf(summary, "| %s | n/a | n/a | n/a | n/a | n/a |\n", unlit[i]);
    fprintf(summary, "\nn/a: no frame of these methods holds any indirect light: the method found no light it "
                     "can use in this scene (e.g. a reflective-shadow-map method on a scene lit only by emissive "
                     "triangles), so its numbers would measure nothing.\n");
}

/* --frames A:B: the references' frames A..B-1 of every sequence, nothing
 * else (the top comment). Every sequence is read and the range checked
 * against it before anything renders. */
static int ev__run_ranged(ev__args *ap)
{
    uint32_t end[EV_MAX_ITEMS], longest = 0, todo = 0;
    for (uint32_t s = 0; s < ap->sequence_count; s++) {
        pf_sequence seq;
        pf_error err;
        if (pf_sequence_load(&seq, ap->sequences[s], &err) != PF_OK) return app_fail(&err);
        uint32_t n = seq.frames;
        pf_sequence_free(&seq);
        if (n > longest) longest = n;
        end[s] = ap->frame_first >= n ? 0 : ap->frame_end < n ? ap->frame_end : n;
        todo += end[s] != 0;
    }
    if (!todo) {
        char given[32];
        if (ap->frame_end == PF_CLI_FRAMES_END) snprintf(given, sizeof given, "%u:", ap->frame_first);
        else snprintf(given, sizeof given, "%u:%u", ap->frame_first, ap->frame_end);
        char m[96];
        snprintf(m, sizeof m, "the longest sequence has %u frames (0..%u)", longest, longest - 1);
        return ev__fail(2, "--frames '%s': no sequence has these frames: %s", given, m);
    }
    ap->steps_total = todo;
    const ev__args *a = ap;
    int worst = 0;
    for (uint32_t s = 0; s < a->sequence_count; s++) {
        char name[256], ref_dir[2500];
        ev__sequence_name(a->sequences[s], name, sizeof name);
        snprintf(ref_dir, sizeof ref_dir, "%s/%s/reference", a->out, name);
        ev__progress_clear(a);
        if (!end[s]) {
            if (!a->quiet) printf("evaluate: %s ends before frame %u: nothing to render\n", name, a->frame_first);
            continue;
        }
        if (!a->quiet) printf("evaluate: %s (%s), reference frames %u..%u\n", name, a->sequences[s], a->frame_first,
                              end[s] - 1);
        ev__progress(a, name, "reference");
        int rc = ev__reference(a, a->sequences[s], ref_dir, a->frame_first, end[s]);
        ap->steps_done++;
        if (rc) worst = rc;
    }
    ev__progress_clear(a);
    if (!a->quiet)
        printf("evaluate --frames: references written to %s; when every range is there, run softgi evaluate with the "
               "same options and no --frames for the methods and tables\n",
               a->out);
    return worst;
}

static int ev__run(ev__args *ap, char (*names)[2600], app_progress *bar, int argc, char **argv)
{
    int help = 0;
    int rc = ev__parse(ap, argc, argv, &help);
    if (rc) return rc;
    if (help) {
        ev__usage(stdout);
        return 0;
    }
    if (ap->quality) {
        app_quality_args q = {.methods = ap->methods, .method_count = ap->method_count, .params = ap->params,
                              .param_count = ap->param_count, .out = ap->out, .table = ap->table,
                              .scene_list = ap->quality_scenes, .scenes_dir = ap->scenes_dir, .size = ap->size,
                              .spp = ap->spp, .vpls = ap->vpls, .proxy_vpls = ap->proxy_vpls,
                              .threads = ap->threads, .isa = ap->isa, .rerun_reference = ap->rerun_reference,
                              .quiet = ap->quiet};
        return app_quality(&q, argc, argv);
    }
    app_progress_begin(bar, "evaluate", ap->quiet);
    ap->bar = bar;
    if (ap->ranged) return ev__run_ranged(ap);
    ap->steps_total = ap->sequence_count * (ap->method_count + 1);
    const ev__args *a = ap;
    char all_table[4300];
    snprintf(all_table, sizeof all_table, "%s/table.md", a->out);
    /* a failure to write the summary is found now, not after hours of rendering */
    pf_error err;
    pf_file probe;
    if (pf_file_begin(&probe, all_table, &err) != PF_OK) return app_fail(&err);
    pf_file_abort(&probe);
    char *summary_text = NULL;
    size_t summary_len = 0;
    FILE *summary = open_memstream(&summary_text, &summary_len);
    if (!summary) return ev__fail(1, "%s: out of memory%s", all_table, "");
    fprintf(summary, "# softgi evaluate\n\nSettings: size %s, reference %s spp, %s VPLs, %s.\n", a->size, a->spp, a->vpls,
            a->full ? "whole images" : "indirect light only");
    int worst = 0;
    for (uint32_t s = 0; s < a->sequence_count; s++) {
        char name[256], seq_dir[2400], ref_dir[2500];
        ev__sequence_name(a->sequences[s], name, sizeof name);
        snprintf(seq_dir, sizeof seq_dir, "%s/%s", a->out, name);
        snprintf(ref_dir, sizeof ref_dir, "%s/reference", seq_dir);
        ev__progress_clear(a);
        if (!a->quiet) printf("evaluate: %s (%s)\n", name, a->sequences[s]);
        fprintf(summary, "\n## %s\n\n", name);
        ev__progress(a, name, "reference");
        rc = ev__reference(a, a->sequences[s], ref_dir, 0, 0);
        ap->steps_done++;
        if (rc) {
            fprintf(summary, "The reference failed (exit %d); sequence skipped.\n", rc);
            worst = rc;
            continue;
        }
        uint32_t ok = 0, dark = 0;
        const char *unlit[EV_MAX_ITEMS];
        for (uint32_t m = 0; m < a->method_count; m++) {
            char dir[2500];
            snprintf(dir, sizeof dir, "%s/%s", seq_dir, a->methods[m]);
            ev__progress(a, name, a->methods[m]);
            rc = ev__method(a, a->sequences[s], a->methods[m], dir);
            ap->steps_done++;
            if (rc) {
                fprintf(summary, "- `%s` failed (exit %d): see the message above; not in the table.\n",
                        a->methods[m], rc);
                continue;
            }
            if (!a->full && ev__has_light(dir) == 0) {
                unlit[dark++] = a->methods[m];
                continue;
            }
            snprintf(names[ok++], sizeof names[0], "%s:%s", a->methods[m], dir);
        }
        if (!ok) {
            fprintf(summary, "No method rendered indirect light in this sequence.\n");
            ev__unlit_rows(summary, unlit, dark);
            continue;
        }
        rc = ev__compare(seq_dir, ref_dir, names, ok);
        if (rc) {
            fprintf(summary, "softgi compare failed (exit %d).\n", rc);
            worst = rc;
            continue;
        }
        char table[2600];
        snprintf(table, sizeof table, "%s/table.md", seq_dir);
        fprintf(summary, "\n");
        ev__append_file(summary, table);
        ev__unlit_rows(summary, unlit, dark);
        fprintf(summary, "\nPlot: `%s/plot.svg`.\n", seq_dir);
    }
    int bad = ferror(summary) != 0;
    bad |= fclose(summary) != 0;
    pf_result r = bad ? pf_error_set(&err, PF_ERR_OUT_OF_MEMORY, "%s: out of memory", all_table)
                      : pf_imageio_write_file(all_table, summary_text, summary_len, &err);
    free(summary_text);
    if (r != PF_OK) return app_fail(&err);
    ev__progress_clear(a);
    if (!a->quiet) printf("evaluate: wrote %s\n", all_table);
    return worst;
}

int app_evaluate(int argc, char **argv)
{
    ev__args *ap = calloc(1, sizeof *ap);
    char(*names)[2600] = calloc(EV_MAX_ITEMS, sizeof *names);
    if (!ap || !names) {
        free(ap), free(names);
        return ev__fail(1, "out of memory%s%s", "", "");
    }
    app_progress bar = {0};
    int rc = ev__run(ap, names, &bar, argc, argv);
    app_progress_end(&bar);
    free(ap), free(names);
    return rc;
}
