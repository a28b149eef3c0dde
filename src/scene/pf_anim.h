/* pf_anim: glTF 2.0 animations, skins and morph targets, and the posing of
 * the flattened scene (pf_scene.h) at a time t. Plain C data with one owner
 * (pf_anim), freed by one call (pf_anim_free); filled by the glTF loader
 * (pf_gltf.cpp, which does all the parsing and checking of the file).
 *
 * What it implements (glTF 2.0 specification):
 * - Sec. 3.11 animations: channels animating a node's translation, rotation,
 *   scale or morph-target weights; samplers with LINEAR, STEP and
 *   CUBICSPLINE interpolation (Appendix C, "Animation Sampler Interpolation
 *   Modes"). LINEAR rotations are spherical linear interpolations on the
 *   shortest path (the keys' dot product negative: the second key negated);
 *   CUBICSPLINE keys are (in-tangent, value, out-tangent) triplets whose
 *   tangents are scaled by the key interval t_{k+1} - t_k (Appendix C's
 *   Hermite form); a CUBICSPLINE rotation is normalised afterwards.
 * - Sec. 3.7.3 skins: joint matrix k = world(joint k) x inverseBindMatrix k
 *   (identity when the skin has none); a vertex skinned by
 *   sum over its influences of weight x joint matrix, over every
 *   JOINTS_n / WEIGHTS_n set, straight into world space: the skinned mesh
 *   node's own transform is ignored (Sec. 3.7.3.1). The skin's `skeleton`
 *   is a hint and not read.
 * - Sec. 3.7.2.2 morph targets: POSITION and NORMAL deltas added with the
 *   weights: the animated ones, else the node's `weights`, else the mesh's,
 *   else zero; then the node's (or the skin's) transform.
 *
 * Time. t is in seconds from the start of the animations (glTF sampler
 * inputs are times from t = 0). Before a sampler's first key its first
 * value holds, after its last key its last value (the spec's clamping;
 * a CUBICSPLINE sampler holds its first or last *value*, not a tangent).
 * Playing "every animation" (PF_ANIM_ALL, softgi's default) applies the
 * file's animations together in file order, each channel in order: where
 * two animate the same property of a node the later one wins.
 * PF_ANIM_STATIC applies none: the file's own node transforms and default
 * weights, which is what the loader's flattened scene is (pf_gltf.h: skinned
 * and morphed primitives are loaded in that pose).
 *
 * Posing a flattened scene (pf_anim_pose). The loader keeps, for every
 * instanced primitive (a mesh primitive under one node), where its vertices
 * and triangles are in the scene arrays, and for the ones an animation can
 * move (`dynamic`: its node or an ancestor animated; for a skinned one any
 * joint or its ancestors; or its morph weights animated) the rest-pose data
 * in the primitive's own space: positions, normals, morph deltas, joints
 * and weights. pf_anim_pose rewrites those primitives' positions and unit
 * normals (flat-shaded primitives, glTF's "no NORMAL", get their face
 * normals again) and the scene's bounds, keeping the vertex and triangle
 * counts and order: triangle ids are stable across frames. It reports, per
 * instanced primitive, whether anything of it moved and its world bounds
 * before and after (pf_anim_moved), so a renderer can redo only what moved
 * geometry can change.
 *
 * Determinism. Posing is a fixed sequence of IEEE operations (node chains in
 * double, in the loader's order; no threads): the same (animation, t) gives
 * the same bytes, whatever was posed before, and PF_ANIM_STATIC gives back
 * the bytes the loader wrote. Slerp uses no libm function: the coefficients
 * sin((1-s)theta)/sin(theta) and sin(s theta)/sin(theta) are evaluated as
 * Eberly's series (D. Eberly, "A Fast and Accurate Algorithm for Computing
 * SLERP", Journal of Graphics, GPU, and Game Tools 15(3), 2011, Sec. 2) with
 * 32 terms in double (within 1e-11 of the exact coefficients at every angle,
 * checked against acos/sin), so a pose is the same on every machine.
 *
 * Deviations and limits (docs/scenes.md, "Animation"):
 * - cameras and lights stay where the static pose puts them (animated
 *   camera or light nodes move their child meshes, not the camera/light);
 * - winding is decided at load from the static pose (glTF's mirroring rule);
 *   a pose that mirrors a primitive the other way keeps it (softgi shades
 *   both sides alike), while normals always follow the pose;
 * - skinned primitives keep the file's winding (no mirroring test);
 * - triangles dropped at load as zero-area stay dropped, and a triangle a
 *   pose makes degenerate stays, with face normal (0, 1, 0) when flat;
 * - TANGENT morph deltas, KHR_animation_pointer and channels without a
 *   target node are ignored (the last two with a load warning).
 *
 * Limits (checked by the loader, pf_gltf.h; docs/security.md): every
 * animation time finite, >= 0 and strictly increasing per sampler, at most
 * PF_ANIM_MAX_TIME; every key finite (rotation values not zero); output
 * counts exactly keys x (3 for CUBICSPLINE) x (targets for weights); at most
 * PF_ANIM_MAX_TARGETS morph targets a mesh, PF_ANIM_MAX_JOINTS joints a skin,
 * PF_ANIM_MAX_SETS JOINTS_n sets; joint indices below the skin's joint
 * count; every joint a node of the scene; and everything kept within the
 * memory budget (pf_budget.h). */
#ifndef PF_ANIM_H
#define PF_ANIM_H

#include <stddef.h>
#include <stdint.h>

#include "pf_math.h"
#include "pf_result.h"
#include "pf_scene.h"

#ifdef __cplusplus
extern "C" {
#endif

#define PF_ANIM_MAX_TIME 1.0e6     /* seconds: keys, --time and sequence times (11.6 days) */
#define PF_ANIM_MAX_TARGETS 256u   /* morph targets of one mesh */
#define PF_ANIM_MAX_JOINTS 65536u  /* joints of one skin (JOINTS_n are u8 or u16) */
#define PF_ANIM_MAX_SETS 8u        /* JOINTS_0..JOINTS_7 / WEIGHTS_0..WEIGHTS_7 */

/* pf_anim_pose's `clip`: an animation index, or one of these. */
#define PF_ANIM_ALL (-1)    /* every animation of the file, together, in file order */
#define PF_ANIM_STATIC (-2) /* no animation: the file's static pose (as loaded) */

typedef enum pf_anim_path {
    PF_ANIM_TRANSLATION = 0, /* 3 floats */
    PF_ANIM_ROTATION,        /* 4: quaternion x, y, z, w */
    PF_ANIM_SCALE,           /* 3 */
    PF_ANIM_WEIGHTS          /* the node's mesh's morph-target count */
} pf_anim_path;

typedef enum pf_anim_interp { PF_ANIM_LINEAR = 0, PF_ANIM_STEP, PF_ANIM_CUBICSPLINE } pf_anim_interp;

/* One glTF animation sampler: key_count times and their values. */
typedef struct pf_anim_sampler {
    pf_anim_interp interp;
    uint32_t key_count; /* >= 1 */
    uint32_t dim;       /* floats per value: 3, 4, or the target count (weights) */
    float *times;       /* key_count, >= 0, strictly increasing, <= PF_ANIM_MAX_TIME */
    float *values;      /* key_count x dim, or for CUBICSPLINE key_count x 3 x dim:
                           (in-tangent, value, out-tangent) per key */
} pf_anim_sampler;

typedef struct pf_anim_channel {
    uint32_t sampler; /* in its animation's samplers */
    uint32_t node;    /* the glTF node */
    pf_anim_path path;
} pf_anim_channel;

/* One glTF animation. */
typedef struct pf_anim_clip {
    char name[64];
    uint32_t sampler_count, channel_count;
    pf_anim_sampler *samplers;
    pf_anim_channel *channels;
    float start, end; /* the first and the last key time over its samplers */
} pf_anim_clip;

/* One glTF node: its static transform and morph weights. */
typedef struct pf_anim_node {
    int32_t parent;          /* -1: a root of the scene (or not in the scene) */
    int in_scene;            /* reached from the scene's roots (the loader's walk) */
    int has_matrix;          /* `matrix` given: never animated (glTF 2.0 Sec. 3.11) */
    pf_mat4 matrix;          /* has_matrix: the file's */
    double t[3], r[4], s[3]; /* otherwise the static TRS, r normalised */
    uint32_t weight_count;   /* its mesh's morph-target count (0: none) */
    float *rest_weights;     /* weight_count: node.weights, else mesh.weights, else 0 */
    float *weights;          /* weight_count: of the last evaluation */
} pf_anim_node;

typedef struct pf_anim_skin {
    uint32_t joint_count; /* 1..PF_ANIM_MAX_JOINTS */
    uint32_t *joints;     /* glTF nodes, each in the scene */
    pf_mat4 *ibm;         /* inverse bind matrices (identity when the file has none) */
    pf_mat4 *joint_mats;  /* world(joint) x ibm of the last evaluation */
    int used;             /* a mesh node of the scene uses it */
} pf_anim_skin;

/* One instanced primitive: mesh `mesh`'s primitive `prim` under node `node`. */
typedef struct pf_anim_prim {
    /* where it lies in the scene's arrays (contiguous) */
    uint32_t vertex_first, vertex_count;
    uint32_t tri_first, tri_count;
    uint32_t node, mesh, prim; /* glTF indices (for messages) */
    int32_t skin;              /* -1: rigid (the node's world matrix) */
    int flat;                  /* no NORMAL: one vertex per triangle corner, face normals */
    int mirror;                /* winding flipped at load (the static world matrix mirrors) */
    int dynamic;               /* an animation can move it: the data below are kept */
    /* the primitive's own data (dynamic only; NULL / 0 otherwise) */
    uint32_t local_count;      /* the file's vertices */
    pf_vec3 *local_pos;        /* local_count */
    pf_vec3 *local_nrm;        /* local_count; NULL when flat */
    uint32_t *src;             /* flat: vertex_count, the file vertex of each scene vertex; NULL: identity */
    uint32_t target_count;     /* morph targets (= its node's weight_count) */
    pf_vec3 *target_pos;       /* target_count x local_count POSITION deltas, or NULL (all zero) */
    pf_vec3 *target_nrm;       /* likewise NORMAL deltas (NULL when flat or none) */
    uint32_t joint_sets;       /* skinned: JOINTS_n/WEIGHTS_n sets, 4 influences each */
    uint16_t *joint;           /* local_count x 4 x joint_sets, each < the skin's joint count */
    float *weight;             /* local_count x 4 x joint_sets, finite */
} pf_anim_prim;

/* Everything posing needs; zero-initialised is an empty anim (a static file). */
typedef struct pf_anim {
    uint32_t node_count;
    pf_anim_node *nodes;     /* the file's nodes */
    uint32_t order_count;
    uint32_t *order;         /* the scene's nodes, parents first (the loader's walk order) */
    pf_mat4 *world;          /* node_count: world matrices of the last evaluation */
    uint32_t skin_count;
    pf_anim_skin *skins;
    uint32_t clip_count;
    pf_anim_clip *clips;
    uint32_t prim_count;
    pf_anim_prim *prims;     /* every instanced primitive, in scene order */
    uint32_t dynamic_count;  /* of them, the ones an animation can move */
    uint32_t max_local;      /* the largest dynamic local_count (scratch size) */
    pf_vec3 *scratch_pos, *scratch_nrm;
    double *trs;             /* node_count x 10 (t, r, s) scratch of an evaluation */
    int32_t pose_clip;       /* the scene's pose: PF_ANIM_STATIC after loading */
    double pose_time;
    uint64_t memory_bytes;   /* what the loader took from the budget for it */
} pf_anim;

/* What one pose did to one instanced primitive (pf_anim_pose's report). */
typedef struct pf_anim_moved {
    uint32_t vertex_first, vertex_count, tri_first, tri_count;
    int moved;                      /* a position or normal changed (bits) */
    pf_vec3 before_min, before_max; /* world bounds of its vertices before the pose */
    pf_vec3 after_min, after_max;   /* and after */
} pf_anim_moved;

void pf_anim_free(pf_anim *anim);
/* Frees a primitive's own data (its arrays, then NULL); the loader's and
 * pf_anim_free's one way to do it. */
void pf_anim_prim_free(pf_anim_prim *p);

/* The animation `name` (when not NULL; the first of that name) or the
 * animation `index` into *clip. PF_ERR_ARGUMENT, with the file's
 * animations listed, when there is none such or the file has none. */
pf_result pf_anim_find(const pf_anim *anim, const char *name, int64_t index, int32_t *clip, pf_error *err);

/* The time range [0, end] the clip (or PF_ANIM_ALL) spans: its last key. */
double pf_anim_end(const pf_anim *anim, int32_t clip);

/* Poses `scene` (loaded with `anim`, perhaps with emitters appended after
 * it) at time t (seconds, finite, in [0, PF_ANIM_MAX_TIME]) of animation
 * `clip` (an index, PF_ANIM_ALL or PF_ANIM_STATIC): rewrites the dynamic
 * primitives' positions and normals and the scene's bounds (as
 * pf_scene_validate computes them). moved (NULL, or anim->prim_count
 * entries) gets what happened to each instanced primitive; *moved_count
 * (may be NULL) how many moved. Fails (PF_ERR_NONFINITE, naming the
 * animation, the time, the mesh, node and vertex) when a posed position is
 * not finite or beyond PF_SCENE_MAX_COORD; the scene is then left in its
 * previous pose, bit for bit. PF_ERR_ARGUMENT for a bad t or clip. */
pf_result pf_anim_pose(pf_scene *scene, pf_anim_moved *moved, uint32_t *moved_count, pf_anim *anim, int32_t clip,
                       double t, pf_error *err);

/* ---------------------------------------------------------------- for the loader
 * pf_gltf.cpp builds the pf_anim and poses the primitives it flattens with
 * the same code (so that PF_ANIM_STATIC gives the loader's bytes). */

/* The column-major matrix T R S of a translation, a unit quaternion
 * (x, y, z, w) and a scale, in double: the loader's node transform. */
pf_mat4 pf_anim_trs_matrix(const double t[3], const double q[4], const double s[3]);

/* pf_v3_normalize_safe, or zero where that is not finite (a denormal
 * largest component without DAZ): every normal the loader and posing make. */
pf_vec3 pf_anim_unit(pf_vec3 v);

/* Evaluates the nodes (local TRS, then world matrices in `order`), morph
 * weights and skins' joint matrices for `clip` at t. */
void pf_anim_evaluate(pf_anim *anim, int32_t clip, double t);

/* Primitive p posed by the last evaluation, per file vertex: world
 * positions into pos[local_count], unit world normals (zero where they
 * vanish) into nrm[local_count] unless p is flat. Returns the first vertex
 * whose position is not finite or beyond PF_SCENE_MAX_COORD, or UINT32_MAX. */
uint32_t pf_anim_prim_deform(const pf_anim *anim, const pf_anim_prim *p, pf_vec3 *pos, pf_vec3 *nrm);

#ifdef __cplusplus
}
#endif

#endif
