/* gi_dump: `--dump-stages DIR [--dump-format png|exr|both]`, every stage of
 * a frame as files a learner can open without a display.
 *
 * png (the default): gi_view_render's pictures, DIR/NN-name.png (NN = the
 *   gi_view_id), byte for byte what the stepper of `softgi view` shows, and
 *   DIR/captions.txt ("NN-name.png: description" a line,
 *   gi_view_describe_frame: the step, stage and paper from the stage table,
 *   then what the view shows; for the VPL views the method's paper and why
 *   it chooses VPLs as it does).
 * exr: the stages' float data, DIR/NN-name.exr (OpenEXR, 32-bit float,
 *   pf_exr.h), beside the pictures of the same NN, each with its caption in
 *   the file's "comments" attribute:
 *     00-depth        Y     view depth; +inf where no surface
 *     01-position     RGBA  world x, y, z; A = 1 where a surface, else 0
 *     02-normal       RGBA  unit world normal; A as above
 *     03-albedo       RGBA  linear diffuse albedo; A as above
 *     06-direct       RGB   direct radiance (emission not included)
 *     10-split        RGBA  split G-buffer normals as the n x m tile mosaic
 *                           of the picture; A = 1 on valid texels
 *     11-accumulated  RGB   per-tile irradiance, the same mosaic
 *     12-combined     RGB   irradiance before the filter
 *     13-filtered     RGB   irradiance after the filter
 *     14-final        RGB   the composed linear radiance (the render's image)
 *     20-clamp        Y     per pixel, how many of its tile's VPLs light it
 *                           with the bounded geometry term clamped
 *   Views that are drawings rather than data (primitive ids, the shadow
 *   map, the VPL overlays, a VPL's paraboloid map, the atlas, the tiles,
 *   the method's own view) have no .exr; views the frame does not have
 *   (gi_view_available) have neither file.
 * png also writes DIR/ranges.txt: "NN-name.png: legend" for every picture
 *   with a legend (gi_view_legend: what its colours stand for and the
 *   smallest and largest value they span, as drawn into the picture).
 * both: both sets. With exr in the format, captions.txt lists every file
 * written, one "NN-name.ext: caption" line each.
 * Values: anything but NaN (positions and normals are signed, depth holds
 * +inf); a NaN refuses the file (pf_imageio.h). */
#ifndef GI_DUMP_H
#define GI_DUMP_H

#include "gi_frame.h"
#include "gi_view.h"

typedef enum gi_dump_format {
    GI_DUMP_PNG = 1,  /* the pictures */
    GI_DUMP_EXR = 2,  /* the float data */
    GI_DUMP_BOTH = 3, /* GI_DUMP_PNG | GI_DUMP_EXR */
} gi_dump_format;

/* 1 when view `id` has float data written as NN-name.exr. */
int gi_dump_has_exr(gi_view_id id);

/* Writes the files above for the frame's last render. */
pf_result gi_dump_stages(const gi_frame *f, const char *dir, const gi_view_settings *s, gi_dump_format format,
                         pf_error *err);

#endif
