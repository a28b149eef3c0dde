/* gi_probe: everything one frame computed at one pixel, for the pixel
 * inspector of `softgi view` (click a pixel) and for tests: RenderDoc's
 * "pixel history" for a many-light frame.
 *
 * A probe copies the frame's named buffers (gi_frame.h) at pixel (x, y), in
 * the order of Laine 2007 Sec. 3's outline:
 *   step 1   the G-buffer planes: depth, position, normal, albedo, triangle;
 *   step 5   the direct light (and the emission compose adds);
 *   step 7   the pixel's tile (i, j) = (x mod n, y mod m) and the tile
 *            irradiance at the pixel's place in the split layout (Sec. 5.1);
 *   step 8-9 the combined and the filtered irradiance (Sec. 5.1-5.2);
 *   step 10  the composed radiance;
 * so each value equals, bit for bit, the float data `--dump-format exr`
 * writes at that pixel (gi_dump.h).
 *
 * It then re-evaluates the accumulation at the pixel VPL by VPL with the
 * accumulation's own formula and order (gi_indirect.h, step 7):
 *     E_tile = T * sum over the tile's VPLs of  I G_b V,
 *     G_b = min(cos_r cos_v / r^2, b),  T = n m,
 * V from the VPL's paraboloid map, its imperfect shadow map or an Embree
 * shadow ray, whichever the frame used. Each VPL's part T I G_b V is what
 * it adds to E_tile; `top` lists the largest by luminance. The scalar
 * accumulation is the reference the SIMD one matches bit for bit, and this
 * sum is the scalar one, so tile_sum == tile_e exactly (tests/test_viewer.c
 * checks it for every pixel). A VPL whose paraboloid map misses the pixel
 * counts as `occluded`; one whose unbounded term exceeded b as `clamped`.
 *
 * Pure: reads the frame (its last render), writes *out, allocates nothing.
 * The frame must not change while probing (the viewer probes between
 * frames). Values are linear: radiance in W/(m^2 sr), irradiance in W/m^2. */
#ifndef GI_PROBE_H
#define GI_PROBE_H

#include <stddef.h>
#include <stdint.h>

#include "gi_frame.h"

#define GI_PROBE_TOP 8 /* VPLs listed, the largest contributions first */

/* One VPL's part of the pixel's tile irradiance. */
typedef struct gi_probe_vpl {
    uint32_t index;      /* in the frame's VPL set */
    uint32_t id;         /* its stable id (gi_vpl.id) */
    pf_vec3 pos, nrm, intensity;
    float distance;      /* r, pixel to VPL */
    float g;             /* G_b, the bounded geometry term */
    int clamped;         /* cos cos / r^2 > b: G_b = b */
    pf_vec3 e;           /* T I G_b: its part of tile_e */
} gi_probe_vpl;

typedef struct gi_probe {
    uint32_t x, y;
    /* step 1: the G-buffer */
    int surface;         /* a triangle covers the pixel (else the rest is 0 and final is black) */
    float depth;         /* view depth; +inf where no surface */
    pf_vec3 position, normal, albedo;
    uint32_t prim;       /* triangle index, RS_GBUFFER_EMPTY where no surface */
    uint32_t material;
    pf_vec3 emission;    /* what compose adds (0 without direct light) */
    /* step 5 */
    int has_direct;      /* 0 for --indirect-only */
    pf_vec3 direct;
    /* steps 6-9 (indirect 0: --direct-only, the rest 0) */
    int indirect;
    uint32_t tiles_n, tiles_m;
    uint32_t tile, tile_i, tile_j; /* tile = tile_j n + tile_i */
    uint32_t split;      /* index of the pixel in split layout (gi_split_index) */
    uint32_t mosaic_x, mosaic_y; /* where the split and accumulated views draw it (those views
                                    cut what falls outside the image when the image size is
                                    not a multiple of the tiles) */
    float weight;        /* T = n m */
    uint32_t tile_vpls;  /* VPLs assigned to the tile */
    uint32_t lit;        /* of those, adding light here */
    uint32_t occluded;   /* facing the pixel, but their visibility test failed */
    uint32_t clamped;    /* adding light with G_b = b */
    pf_vec3 tile_e;      /* the frame's tile irradiance (split_e) */
    pf_vec3 tile_sum;    /* the same, re-evaluated VPL by VPL here */
    pf_vec3 combined, filtered;
    uint32_t top_count;
    gi_probe_vpl top[GI_PROBE_TOP];
    /* step 10 */
    pf_vec3 final;
} gi_probe;

/* Probes pixel (x, y) of the frame's last render (x < width, y < height). */
void gi_probe_pixel(gi_probe *out, const gi_frame *f, uint32_t x, uint32_t y);

/* The probe as text lines ("direct 0.1 0.2 0.3\n", ...): `digits`
 * significant digits (9: every float read back exactly; 4 for a HUD); at
 * most `top` VPLs listed. Returns the length written (snprintf's rules). */
int gi_probe_text(char *buf, size_t size, const gi_probe *p, int digits, uint32_t top);

#endif
