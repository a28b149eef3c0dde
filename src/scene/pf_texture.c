/* pf_texture: texture storage and filtering for baseColor textures.
 *
 * - Mip chains are built at load with a 2x2 box filter (odd sizes fold the
 *   last row/column in with 3-tap weights), averaging in linear space and
 *   re-encoding to sRGB, so a mip of a checkerboard stays the right grey.
 * - Sampling follows the glTF sampler: REPEAT/CLAMP/MIRROR wrap, NEAREST or
 *   LINEAR within a level, NEAREST or LINEAR between levels. Texel centres
 *   are at (i + 0.5) / size, as OpenGL defines.
 * - sRGB decode uses a constant 256-entry table (IEC 61966-2-1, computed in
 *   double and rounded to float), so it is exact, fast and shared by every
 *   path. */
#include <stdlib.h>
#include <string.h>

#include "pf_scene.h"

static const float pf__srgb_lut[256] = {
    0.000000000e+00f, 3.035269835e-04f, 6.070539671e-04f, 9.105809506e-04f, 1.214107934e-03f, 1.517634918e-03f, 1.821161901e-03f, 2.124688885e-03f,
    2.428215868e-03f, 2.731742852e-03f, 3.035269835e-03f, 3.346535764e-03f, 3.676507324e-03f, 4.024717018e-03f, 4.391442037e-03f, 4.776953481e-03f,
    5.181516702e-03f, 5.605391624e-03f, 6.048833023e-03f, 6.512090793e-03f, 6.995410187e-03f, 7.499032043e-03f, 8.023192985e-03f, 8.568125618e-03f,
    9.134058702e-03f, 9.721217320e-03f, 1.032982303e-02f, 1.096009401e-02f, 1.161224518e-02f, 1.228648836e-02f, 1.298303234e-02f, 1.370208305e-02f,
    1.444384360e-02f, 1.520851442e-02f, 1.599629337e-02f, 1.680737575e-02f, 1.764195449e-02f, 1.850022013e-02f, 1.938236096e-02f, 2.028856306e-02f,
    2.121901038e-02f, 2.217388479e-02f, 2.315336618e-02f, 2.415763245e-02f, 2.518685963e-02f, 2.624122189e-02f, 2.732089164e-02f, 2.842603950e-02f,
    2.955683444e-02f, 3.071344373e-02f, 3.189603307e-02f, 3.310476657e-02f, 3.433980681e-02f, 3.560131488e-02f, 3.688945040e-02f, 3.820437160e-02f,
    3.954623528e-02f, 4.091519691e-02f, 4.231141062e-02f, 4.373502926e-02f, 4.518620439e-02f, 4.666508634e-02f, 4.817182423e-02f, 4.970656598e-02f,
    5.126945837e-02f, 5.286064702e-02f, 5.448027644e-02f, 5.612849005e-02f, 5.780543019e-02f, 5.951123816e-02f, 6.124605423e-02f, 6.301001765e-02f,
    6.480326669e-02f, 6.662593864e-02f, 6.847816984e-02f, 7.036009570e-02f, 7.227185068e-02f, 7.421356838e-02f, 7.618538148e-02f, 7.818742181e-02f,
    8.021982031e-02f, 8.228270713e-02f, 8.437621154e-02f, 8.650046204e-02f, 8.865558629e-02f, 9.084171118e-02f, 9.305896285e-02f, 9.530746663e-02f,
    9.758734714e-02f, 9.989872825e-02f, 1.022417331e-01f, 1.046164841e-01f, 1.070231030e-01f, 1.094617108e-01f, 1.119324278e-01f, 1.144353738e-01f,
    1.169706678e-01f, 1.195384280e-01f, 1.221387722e-01f, 1.247718176e-01f, 1.274376804e-01f, 1.301364767e-01f, 1.328683216e-01f, 1.356333297e-01f,
    1.384316150e-01f, 1.412632911e-01f, 1.441284709e-01f, 1.470272665e-01f, 1.499597898e-01f, 1.529261520e-01f, 1.559264637e-01f, 1.589608351e-01f,
    1.620293756e-01f, 1.651321945e-01f, 1.682694002e-01f, 1.714411007e-01f, 1.746474037e-01f, 1.778884160e-01f, 1.811642442e-01f, 1.844749945e-01f,
    1.878207723e-01f, 1.912016827e-01f, 1.946178304e-01f, 1.980693196e-01f, 2.015562538e-01f, 2.050787364e-01f, 2.086368701e-01f, 2.122307574e-01f,
    2.158605001e-01f, 2.195261997e-01f, 2.232279573e-01f, 2.269658735e-01f, 2.307400485e-01f, 2.345505822e-01f, 2.383975738e-01f, 2.422811225e-01f,
    2.462013267e-01f, 2.501582847e-01f, 2.541520943e-01f, 2.581828529e-01f, 2.622506575e-01f, 2.663556048e-01f, 2.704977910e-01f, 2.746773121e-01f,
    2.788942635e-01f, 2.831487404e-01f, 2.874408377e-01f, 2.917706498e-01f, 2.961382708e-01f, 3.005437944e-01f, 3.049873141e-01f, 3.094689228e-01f,
    3.139887134e-01f, 3.185467781e-01f, 3.231432091e-01f, 3.277780981e-01f, 3.324515363e-01f, 3.371636150e-01f, 3.419144249e-01f, 3.467040564e-01f,
    3.515325995e-01f, 3.564001441e-01f, 3.613067798e-01f, 3.662525956e-01f, 3.712376805e-01f, 3.762621230e-01f, 3.813260114e-01f, 3.864294338e-01f,
    3.915724777e-01f, 3.967552307e-01f, 4.019777798e-01f, 4.072402119e-01f, 4.125426135e-01f, 4.178850708e-01f, 4.232676700e-01f, 4.286904966e-01f,
    4.341536362e-01f, 4.396571738e-01f, 4.452011945e-01f, 4.507857828e-01f, 4.564110232e-01f, 4.620769997e-01f, 4.677837961e-01f, 4.735314961e-01f,
    4.793201831e-01f, 4.851499401e-01f, 4.910208498e-01f, 4.969329951e-01f, 5.028864580e-01f, 5.088813209e-01f, 5.149176654e-01f, 5.209955732e-01f,
    5.271151257e-01f, 5.332764040e-01f, 5.394794890e-01f, 5.457244614e-01f, 5.520114015e-01f, 5.583403896e-01f, 5.647115057e-01f, 5.711248295e-01f,
    5.775804404e-01f, 5.840784179e-01f, 5.906188409e-01f, 5.972017884e-01f, 6.038273389e-01f, 6.104955708e-01f, 6.172065624e-01f, 6.239603917e-01f,
    6.307571363e-01f, 6.375968740e-01f, 6.444796820e-01f, 6.514056374e-01f, 6.583748173e-01f, 6.653872983e-01f, 6.724431570e-01f, 6.795424696e-01f,
    6.866853124e-01f, 6.938717613e-01f, 7.011018919e-01f, 7.083757799e-01f, 7.156935005e-01f, 7.230551289e-01f, 7.304607401e-01f, 7.379104088e-01f,
    7.454042095e-01f, 7.529422168e-01f, 7.605245047e-01f, 7.681511472e-01f, 7.758222183e-01f, 7.835377915e-01f, 7.912979403e-01f, 7.991027380e-01f,
    8.069522577e-01f, 8.148465722e-01f, 8.227857544e-01f, 8.307698768e-01f, 8.387990117e-01f, 8.468732315e-01f, 8.549926081e-01f, 8.631572135e-01f,
    8.713671192e-01f, 8.796223969e-01f, 8.879231179e-01f, 8.962693534e-01f, 9.046611744e-01f, 9.130986518e-01f, 9.215818563e-01f, 9.301108584e-01f,
    9.386857285e-01f, 9.473065367e-01f, 9.559733532e-01f, 9.646862479e-01f, 9.734452904e-01f, 9.822505503e-01f, 9.911020971e-01f, 1.000000000e+00f,
};

float pf_srgb_to_linear(float c)
{
    if (c <= 0.04045f) return c / 12.92f;
    return powf((c + 0.055f) / 1.055f, 2.4f);
}

float pf_linear_to_srgb(float c)
{
    if (!(c > 0.0f)) return 0.0f;
    if (c >= 1.0f) return 1.0f;
    if (c <= 0.0031308f) return c * 12.92f;
    return 1.055f * powf(c, 1.0f / 2.4f) - 0.055f;
}

static uint8_t pf__encode8(float linear)
{
    float s = pf_linear_to_srgb(linear) * 255.0f + 0.5f;
    return (uint8_t)(s >= 255.0f ? 255 : (s <= 0.0f ? 0 : (int)s));
}

pf_result pf_image_build_mips(pf_image *img, const uint8_t *level0, uint32_t w, uint32_t h, pf_error *err)
{
    if (w == 0 || h == 0 || w > 32768 || h > 32768)
        return pf_error_set(err, PF_ERR_TEXTURE, "texture size %ux%u is outside 1..32768", w, h);
    memset(img, 0, sizeof *img);
    size_t total = 0;
    uint32_t lw = w, lh = h, n = 0;
    for (;;) {
        img->level_w[n] = lw;
        img->level_h[n] = lh;
        img->level_offset[n] = total;
        total += (size_t)lw * lh;
        n++;
        if ((lw == 1 && lh == 1) || n == PF_MAX_MIPS) break;
        lw = lw > 1 ? lw / 2 : 1;
        lh = lh > 1 ? lh / 2 : 1;
    }
    img->texels = malloc(total * 4);
    if (!img->texels) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory for a %ux%u texture", w, h);
    img->width = w;
    img->height = h;
    img->level_count = n;
    memcpy(img->texels, level0, (size_t)w * h * 4);
    for (uint32_t l = 1; l < n; l++) {
        const uint8_t *src = img->texels + img->level_offset[l - 1] * 4;
        uint8_t *dst = img->texels + img->level_offset[l] * 4;
        uint32_t sw = img->level_w[l - 1], sh = img->level_h[l - 1];
        uint32_t dw = img->level_w[l], dh = img->level_h[l];
        /* Source footprint of a destination texel: 2 texels, or 3 at the end
         * of an odd dimension (so no source texel is dropped), 1 when the
         * source is already 1 wide. */
        for (uint32_t y = 0; y < dh; y++) {
            uint32_t y0 = sh == 1 ? 0 : 2 * y;
            uint32_t ny = sh == 1 ? 1 : ((y == dh - 1 && (sh & 1)) ? 3 : 2);
            for (uint32_t x = 0; x < dw; x++) {
                uint32_t x0 = sw == 1 ? 0 : 2 * x;
                uint32_t nx = sw == 1 ? 1 : ((x == dw - 1 && (sw & 1)) ? 3 : 2);
                float acc[4] = {0, 0, 0, 0};
                for (uint32_t j = 0; j < ny; j++)
                    for (uint32_t i = 0; i < nx; i++) {
                        const uint8_t *t = src + ((size_t)(y0 + j) * sw + (x0 + i)) * 4;
                        acc[0] += pf__srgb_lut[t[0]];
                        acc[1] += pf__srgb_lut[t[1]];
                        acc[2] += pf__srgb_lut[t[2]];
                        acc[3] += (float)t[3];
                    }
                float inv = 1.0f / (float)(nx * ny);
                uint8_t *d = dst + ((size_t)y * dw + x) * 4;
                d[0] = pf__encode8(acc[0] * inv);
                d[1] = pf__encode8(acc[1] * inv);
                d[2] = pf__encode8(acc[2] * inv);
                float a = acc[3] * inv + 0.5f;
                d[3] = (uint8_t)(a >= 255.0f ? 255 : (int)a);
            }
        }
    }
    return PF_OK;
}

/* Wraps integer texel coordinate i into [0, n). */
static uint32_t pf__wrap(int64_t i, uint32_t n, pf_wrap mode)
{
    int64_t nn = (int64_t)n;
    switch (mode) {
    case PF_WRAP_CLAMP: return (uint32_t)(i < 0 ? 0 : (i >= nn ? nn - 1 : i));
    case PF_WRAP_MIRROR: {
        int64_t p = i % (2 * nn);
        if (p < 0) p += 2 * nn;
        return (uint32_t)(p < nn ? p : 2 * nn - 1 - p);
    }
    case PF_WRAP_REPEAT:
    default: {
        int64_t p = i % nn;
        return (uint32_t)(p < 0 ? p + nn : p);
    }
    }
}

static void pf__fetch(const pf_image *img, uint32_t level, uint32_t x, uint32_t y, float out[4])
{
    const uint8_t *t = img->texels + (img->level_offset[level] + (size_t)y * img->level_w[level] + x) * 4;
    out[0] = pf__srgb_lut[t[0]];
    out[1] = pf__srgb_lut[t[1]];
    out[2] = pf__srgb_lut[t[2]];
    out[3] = (float)t[3] * (1.0f / 255.0f);
}

/* Keeps texel coordinates in a range where the int64 conversion is exact and
 * the wrap arithmetic cannot overflow (uvs are validated finite at load, but
 * may be large). Wrapping by whole periods first keeps REPEAT/MIRROR exact. */
static float pf__reduce_uv(float u, pf_wrap mode)
{
    if (fabsf(u) < 1.0e6f) return u;
    /* A NaN or infinite uv (barycentrics of a degenerate triangle: 0/0 at
     * an alpha test of the rasterizer, found by fuzz_frame) samples texel
     * (0, 0): the texel index below is converted to an integer, which is
     * undefined for a NaN. Finite uvs keep their bits. */
    if (!isfinite(u)) return 0.0f;
    if (mode == PF_WRAP_CLAMP) return u < 0.0f ? -1.0f : 2.0f;
    return fmodf(u, 2.0f); /* exact at this magnitude; period 2 suits REPEAT and MIRROR */
}

static void pf__sample_level(const pf_image *img, const pf_texture *tex, uint32_t level, pf_vec2 uv, int linear,
                             float out[4])
{
    float w = (float)img->level_w[level], h = (float)img->level_h[level];
    float fx = pf__reduce_uv(uv.x, tex->wrap_s) * w, fy = pf__reduce_uv(uv.y, tex->wrap_t) * h;
    if (!linear) {
        int64_t ix = (int64_t)floorf(fx), iy = (int64_t)floorf(fy);
        pf__fetch(img, level, pf__wrap(ix, img->level_w[level], tex->wrap_s),
                  pf__wrap(iy, img->level_h[level], tex->wrap_t), out);
        return;
    }
    fx -= 0.5f;
    fy -= 0.5f;
    float x0f = floorf(fx), y0f = floorf(fy);
    float ax = fx - x0f, ay = fy - y0f;
    int64_t x0 = (int64_t)x0f, y0 = (int64_t)y0f;
    uint32_t xa = pf__wrap(x0, img->level_w[level], tex->wrap_s), xb = pf__wrap(x0 + 1, img->level_w[level], tex->wrap_s);
    uint32_t ya = pf__wrap(y0, img->level_h[level], tex->wrap_t), yb = pf__wrap(y0 + 1, img->level_h[level], tex->wrap_t);
    float t00[4], t10[4], t01[4], t11[4];
    pf__fetch(img, level, xa, ya, t00);
    pf__fetch(img, level, xb, ya, t10);
    pf__fetch(img, level, xa, yb, t01);
    pf__fetch(img, level, xb, yb, t11);
    for (int k = 0; k < 4; k++) {
        float top = t00[k] + (t10[k] - t00[k]) * ax;
        float bot = t01[k] + (t11[k] - t01[k]) * ax;
        out[k] = top + (bot - top) * ay;
    }
}

void pf_material_sample(const pf_scene *scene, uint32_t material, pf_vec2 uv, float lod, float out[4])
{
    const pf_material *m = &scene->materials[material];
    if (m->base_color_texture < 0) {
        memcpy(out, m->base_color, 4 * sizeof(float));
        return;
    }
    const pf_texture *tex = &scene->textures[m->base_color_texture];
    const pf_image *img = &scene->images[tex->image];
    float t[4];
    if (!(lod > 0.0f) || !tex->min_mipmap) {
        /* magnification (or no mips): level 0 with the mag/min filter */
        int linear = !(lod > 0.0f) ? tex->mag_linear : tex->min_linear;
        pf__sample_level(img, tex, 0, uv, linear, t);
    } else {
        float max_level = (float)(img->level_count - 1);
        float l = lod < max_level ? lod : max_level;
        if (tex->mip_linear) {
            uint32_t l0 = (uint32_t)l;
            uint32_t l1 = l0 + 1 < img->level_count ? l0 + 1 : l0;
            float f = l - (float)l0;
            float a[4], b[4];
            pf__sample_level(img, tex, l0, uv, tex->min_linear, a);
            pf__sample_level(img, tex, l1, uv, tex->min_linear, b);
            for (int k = 0; k < 4; k++) t[k] = a[k] + (b[k] - a[k]) * f;
        } else {
            pf__sample_level(img, tex, (uint32_t)(l + 0.5f), uv, tex->min_linear, t);
        }
    }
    for (int k = 0; k < 4; k++) out[k] = m->base_color[k] * t[k];
}

float pf_material_lod(const pf_scene *scene, uint32_t material, float dudx, float dvdx, float dudy, float dvdy)
{
    const pf_material *m = &scene->materials[material];
    if (m->base_color_texture < 0) return 0.0f;
    const pf_image *img = &scene->images[scene->textures[m->base_color_texture].image];
    float w = (float)img->width, h = (float)img->height;
    float ax = dudx * w, ay = dvdx * h, bx = dudy * w, by = dvdy * h;
    float rho2 = fmaxf(ax * ax + ay * ay, bx * bx + by * by); /* OpenGL 4.6 Eq. 8.7, squared */
    if (!(rho2 > 1.0f)) return 0.0f;
    float lod = 0.5f * log2f(rho2);
    return isfinite(lod) ? lod : (float)(PF_MAX_MIPS - 1);
}
