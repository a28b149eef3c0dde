/* rs_gbuffer: G-buffer planes (see rs_gbuffer.h). */
#include "rs_gbuffer.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

pf_result rs_gbuffer_init(rs_gbuffer *g, uint32_t width, uint32_t height, pf_error *err)
{
    memset(g, 0, sizeof *g);
    size_t n = (size_t)width * height;
    g->width = width;
    g->height = height;
    float **planes[] = {&g->depth, &g->pos_x, &g->pos_y, &g->pos_z, &g->nrm_x,
                        &g->nrm_y, &g->nrm_z, &g->alb_r, &g->alb_g, &g->alb_b};
    for (size_t i = 0; i < sizeof planes / sizeof planes[0]; i++)
        if (!(*planes[i] = calloc(n ? n : 1, sizeof(float)))) goto oom;
    if (!(g->prim = calloc(n ? n : 1, sizeof(uint32_t)))) goto oom;
    rs_gbuffer_clear(g);
    return PF_OK;
oom:
    rs_gbuffer_free(g);
    return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory for a %ux%u G-buffer", width, height);
}

void rs_gbuffer_clear(rs_gbuffer *g)
{
    size_t n = (size_t)g->width * g->height;
    for (size_t i = 0; i < n; i++) {
        g->depth[i] = INFINITY;
        g->prim[i] = RS_GBUFFER_EMPTY;
    }
}

void rs_gbuffer_free(rs_gbuffer *g)
{
    free(g->depth);
    free(g->pos_x);
    free(g->pos_y);
    free(g->pos_z);
    free(g->nrm_x);
    free(g->nrm_y);
    free(g->nrm_z);
    free(g->alb_r);
    free(g->alb_g);
    free(g->alb_b);
    free(g->prim);
    memset(g, 0, sizeof *g);
}
