/*
 * teapot.c - Newell's teapot: 32 bicubic Bezier patches, tessellated.
 *
 * The control points are Martin Newell's 1975 teapot, as published by Frank
 * Crow, "The Origins of the Teapot", IEEE CG&A 7(1), January 1987, with the
 * four bottom patches Crow added, in the patch order and 0-based numbering of
 * Eric Haines' SPD teapot (rim 4, body 8, handle 4, spout 4, lid 8, bottom 4).
 * Crow's list has duplicate points (his 93 and 271) and unused ones; they are
 * kept so that the indices stay those of the published table. z is up, the
 * teapot stands on z = 0; it spans about x -3..3.525, y -2..2, z 0..3.15.
 *
 * Tessellation: each patch is sampled on an (n+1) x (n+1) grid of (s, t) =
 * (i/n, j/n), s along the rows of the control net, and every grid square is
 * cut into the triangles (s,t)(s,t+1)(s+1,t+1) and (s+1,t+1)(s+1,t)(s,t),
 * as in the SPD. Eight patches (the lid knob and the bottom centre) have a
 * whole row of coincident control points; the zero-area triangles along that
 * row are not emitted (as in the SPD): 64 n^2 - 8 n triangles in all.
 *
 * Neighbouring patches share their boundary control points, sometimes with
 * the edge running the other way. The cubic is evaluated from the weight
 * pair (1-t, t) = ((n-j)/n, j/n) in a form that is symmetric under reversing
 * both the points and the parameter, and exact at both ends, so a shared edge
 * gives bit-identical vertices on both sides: no cracks between patches.
 */
#include <stdlib.h>

#include "scene/mesh.h"
#include "scene/teapot.h"

#define TEAPOT_PATCHES 32
#define TEAPOT_POINTS 290

/* Control points, 0-based (the SPD numbering). */
static const float teapot_points[TEAPOT_POINTS][3] = {
    /* 0: rim */
    {1.4f, 0.0f, 2.4f}, {1.4f, -0.784f, 2.4f}, {0.784f, -1.4f, 2.4f}, {0.0f, -1.4f, 2.4f},
    {1.3375f, 0.0f, 2.53125f}, {1.3375f, -0.749f, 2.53125f}, {0.749f, -1.3375f, 2.53125f},
    {0.0f, -1.3375f, 2.53125f}, {1.4375f, 0.0f, 2.53125f}, {1.4375f, -0.805f, 2.53125f},
    {0.805f, -1.4375f, 2.53125f}, {0.0f, -1.4375f, 2.53125f}, {1.5f, 0.0f, 2.4f},
    {1.5f, -0.84f, 2.4f}, {0.84f, -1.5f, 2.4f}, {0.0f, -1.5f, 2.4f},
    /* 16 */
    {-0.784f, -1.4f, 2.4f}, {-1.4f, -0.784f, 2.4f}, {-1.4f, 0.0f, 2.4f},
    {-0.749f, -1.3375f, 2.53125f}, {-1.3375f, -0.749f, 2.53125f}, {-1.3375f, 0.0f, 2.53125f},
    {-0.805f, -1.4375f, 2.53125f}, {-1.4375f, -0.805f, 2.53125f}, {-1.4375f, 0.0f, 2.53125f},
    {-0.84f, -1.5f, 2.4f}, {-1.5f, -0.84f, 2.4f}, {-1.5f, 0.0f, 2.4f},
    /* 28 */
    {-1.4f, 0.784f, 2.4f}, {-0.784f, 1.4f, 2.4f}, {0.0f, 1.4f, 2.4f},
    {-1.3375f, 0.749f, 2.53125f}, {-0.749f, 1.3375f, 2.53125f}, {0.0f, 1.3375f, 2.53125f},
    {-1.4375f, 0.805f, 2.53125f}, {-0.805f, 1.4375f, 2.53125f}, {0.0f, 1.4375f, 2.53125f},
    {-1.5f, 0.84f, 2.4f}, {-0.84f, 1.5f, 2.4f}, {0.0f, 1.5f, 2.4f},
    /* 40 */
    {0.784f, 1.4f, 2.4f}, {1.4f, 0.784f, 2.4f}, {0.749f, 1.3375f, 2.53125f},
    {1.3375f, 0.749f, 2.53125f}, {0.805f, 1.4375f, 2.53125f}, {1.4375f, 0.805f, 2.53125f},
    {0.84f, 1.5f, 2.4f}, {1.5f, 0.84f, 2.4f},
    /* 48: body */
    {1.75f, 0.0f, 1.875f}, {1.75f, -0.98f, 1.875f}, {0.98f, -1.75f, 1.875f},
    {0.0f, -1.75f, 1.875f}, {2.0f, 0.0f, 1.35f}, {2.0f, -1.12f, 1.35f}, {1.12f, -2.0f, 1.35f},
    {0.0f, -2.0f, 1.35f}, {2.0f, 0.0f, 0.9f}, {2.0f, -1.12f, 0.9f}, {1.12f, -2.0f, 0.9f},
    {0.0f, -2.0f, 0.9f},
    /* 60 */
    {-0.98f, -1.75f, 1.875f}, {-1.75f, -0.98f, 1.875f}, {-1.75f, 0.0f, 1.875f},
    {-1.12f, -2.0f, 1.35f}, {-2.0f, -1.12f, 1.35f}, {-2.0f, 0.0f, 1.35f}, {-1.12f, -2.0f, 0.9f},
    {-2.0f, -1.12f, 0.9f}, {-2.0f, 0.0f, 0.9f},
    /* 69 */
    {-1.75f, 0.98f, 1.875f}, {-0.98f, 1.75f, 1.875f}, {0.0f, 1.75f, 1.875f},
    {-2.0f, 1.12f, 1.35f}, {-1.12f, 2.0f, 1.35f}, {0.0f, 2.0f, 1.35f}, {-2.0f, 1.12f, 0.9f},
    {-1.12f, 2.0f, 0.9f}, {0.0f, 2.0f, 0.9f},
    /* 78 */
    {0.98f, 1.75f, 1.875f}, {1.75f, 0.98f, 1.875f}, {1.12f, 2.0f, 1.35f}, {2.0f, 1.12f, 1.35f},
    {1.12f, 2.0f, 0.9f}, {2.0f, 1.12f, 0.9f},
    /* 84 */
    {2.0f, 0.0f, 0.45f}, {2.0f, -1.12f, 0.45f}, {1.12f, -2.0f, 0.45f}, {0.0f, -2.0f, 0.45f},
    {1.5f, 0.0f, 0.225f}, {1.5f, -0.84f, 0.225f}, {0.84f, -1.5f, 0.225f},
    {0.0f, -1.5f, 0.225f}, {1.5f, 0.0f, 0.15f}, {1.5f, -0.84f, 0.15f}, {0.84f, -1.5f, 0.15f},
    {0.0f, -1.5f, 0.15f},
    /* 96 */
    {-1.12f, -2.0f, 0.45f}, {-2.0f, -1.12f, 0.45f}, {-2.0f, 0.0f, 0.45f},
    {-0.84f, -1.5f, 0.225f}, {-1.5f, -0.84f, 0.225f}, {-1.5f, 0.0f, 0.225f},
    {-0.84f, -1.5f, 0.15f}, {-1.5f, -0.84f, 0.15f}, {-1.5f, 0.0f, 0.15f},
    /* 105 */
    {-2.0f, 1.12f, 0.45f}, {-1.12f, 2.0f, 0.45f}, {0.0f, 2.0f, 0.45f},
    {-1.5f, 0.84f, 0.225f}, {-0.84f, 1.5f, 0.225f}, {0.0f, 1.5f, 0.225f},
    {-1.5f, 0.84f, 0.15f}, {-0.84f, 1.5f, 0.15f}, {0.0f, 1.5f, 0.15f},
    /* 114 */
    {1.12f, 2.0f, 0.45f}, {2.0f, 1.12f, 0.45f}, {0.84f, 1.5f, 0.225f}, {1.5f, 0.84f, 0.225f},
    {0.84f, 1.5f, 0.15f}, {1.5f, 0.84f, 0.15f},
    /* 120: handle */
    {-1.6f, 0.0f, 2.025f}, {-1.6f, -0.3f, 2.025f}, {-1.5f, -0.3f, 2.25f},
    {-1.5f, 0.0f, 2.25f}, {-2.3f, 0.0f, 2.025f}, {-2.3f, -0.3f, 2.025f},
    {-2.5f, -0.3f, 2.25f}, {-2.5f, 0.0f, 2.25f}, {-2.7f, 0.0f, 2.025f},
    {-2.7f, -0.3f, 2.025f}, {-3.0f, -0.3f, 2.25f}, {-3.0f, 0.0f, 2.25f},
    {-2.7f, 0.0f, 1.8f}, {-2.7f, -0.3f, 1.8f}, {-3.0f, -0.3f, 1.8f}, {-3.0f, 0.0f, 1.8f},
    /* 136 */
    {-1.5f, 0.3f, 2.25f}, {-1.6f, 0.3f, 2.025f}, {-2.5f, 0.3f, 2.25f}, {-2.3f, 0.3f, 2.025f},
    {-3.0f, 0.3f, 2.25f}, {-2.7f, 0.3f, 2.025f}, {-3.0f, 0.3f, 1.8f}, {-2.7f, 0.3f, 1.8f},
    /* 144 */
    {-2.7f, 0.0f, 1.575f}, {-2.7f, -0.3f, 1.575f}, {-3.0f, -0.3f, 1.35f},
    {-3.0f, 0.0f, 1.35f}, {-2.5f, 0.0f, 1.125f}, {-2.5f, -0.3f, 1.125f},
    {-2.65f, -0.3f, 0.9375f}, {-2.65f, 0.0f, 0.9375f}, {-2.0f, -0.3f, 0.9f},
    {-1.9f, -0.3f, 0.6f}, {-1.9f, 0.0f, 0.6f},
    /* 155 */
    {-3.0f, 0.3f, 1.35f}, {-2.7f, 0.3f, 1.575f}, {-2.65f, 0.3f, 0.9375f},
    {-2.5f, 0.3f, 1.125f}, {-1.9f, 0.3f, 0.6f}, {-2.0f, 0.3f, 0.9f},
    /* 161: spout */
    {1.7f, 0.0f, 1.425f}, {1.7f, -0.66f, 1.425f}, {1.7f, -0.66f, 0.6f}, {1.7f, 0.0f, 0.6f},
    {2.6f, 0.0f, 1.425f}, {2.6f, -0.66f, 1.425f}, {3.1f, -0.66f, 0.825f},
    {3.1f, 0.0f, 0.825f}, {2.3f, 0.0f, 2.1f}, {2.3f, -0.25f, 2.1f}, {2.4f, -0.25f, 2.025f},
    {2.4f, 0.0f, 2.025f}, {2.7f, 0.0f, 2.4f}, {2.7f, -0.25f, 2.4f}, {3.3f, -0.25f, 2.4f},
    {3.3f, 0.0f, 2.4f},
    /* 177 */
    {1.7f, 0.66f, 0.6f}, {1.7f, 0.66f, 1.425f}, {3.1f, 0.66f, 0.825f}, {2.6f, 0.66f, 1.425f},
    {2.4f, 0.25f, 2.025f}, {2.3f, 0.25f, 2.1f}, {3.3f, 0.25f, 2.4f}, {2.7f, 0.25f, 2.4f},
    /* 185 */
    {2.8f, 0.0f, 2.475f}, {2.8f, -0.25f, 2.475f}, {3.525f, -0.25f, 2.49375f},
    {3.525f, 0.0f, 2.49375f}, {2.9f, 0.0f, 2.475f}, {2.9f, -0.15f, 2.475f},
    {3.45f, -0.15f, 2.5125f}, {3.45f, 0.0f, 2.5125f}, {2.8f, 0.0f, 2.4f},
    {2.8f, -0.15f, 2.4f}, {3.2f, -0.15f, 2.4f}, {3.2f, 0.0f, 2.4f},
    /* 197 */
    {3.525f, 0.25f, 2.49375f}, {2.8f, 0.25f, 2.475f}, {3.45f, 0.15f, 2.5125f},
    {2.9f, 0.15f, 2.475f}, {3.2f, 0.15f, 2.4f}, {2.8f, 0.15f, 2.4f},
    /* 203: lid */
    {0.0f, 0.0f, 3.15f}, {0.8f, 0.0f, 3.15f}, {0.8f, -0.45f, 3.15f}, {0.45f, -0.8f, 3.15f},
    {0.0f, -0.8f, 3.15f}, {0.0f, 0.0f, 2.85f}, {0.2f, 0.0f, 2.7f}, {0.2f, -0.112f, 2.7f},
    {0.112f, -0.2f, 2.7f}, {0.0f, -0.2f, 2.7f},
    /* 213 */
    {-0.45f, -0.8f, 3.15f}, {-0.8f, -0.45f, 3.15f}, {-0.8f, 0.0f, 3.15f},
    {-0.112f, -0.2f, 2.7f}, {-0.2f, -0.112f, 2.7f}, {-0.2f, 0.0f, 2.7f},
    /* 219 */
    {-0.8f, 0.45f, 3.15f}, {-0.45f, 0.8f, 3.15f}, {0.0f, 0.8f, 3.15f},
    {-0.2f, 0.112f, 2.7f}, {-0.112f, 0.2f, 2.7f}, {0.0f, 0.2f, 2.7f},
    /* 225 */
    {0.45f, 0.8f, 3.15f}, {0.8f, 0.45f, 3.15f}, {0.112f, 0.2f, 2.7f}, {0.2f, 0.112f, 2.7f},
    /* 229 */
    {0.4f, 0.0f, 2.55f}, {0.4f, -0.224f, 2.55f}, {0.224f, -0.4f, 2.55f}, {0.0f, -0.4f, 2.55f},
    {1.3f, 0.0f, 2.55f}, {1.3f, -0.728f, 2.55f}, {0.728f, -1.3f, 2.55f}, {0.0f, -1.3f, 2.55f},
    {1.3f, 0.0f, 2.4f}, {1.3f, -0.728f, 2.4f}, {0.728f, -1.3f, 2.4f}, {0.0f, -1.3f, 2.4f},
    /* 241 */
    {-0.224f, -0.4f, 2.55f}, {-0.4f, -0.224f, 2.55f}, {-0.4f, 0.0f, 2.55f},
    {-0.728f, -1.3f, 2.55f}, {-1.3f, -0.728f, 2.55f}, {-1.3f, 0.0f, 2.55f},
    {-0.728f, -1.3f, 2.4f}, {-1.3f, -0.728f, 2.4f}, {-1.3f, 0.0f, 2.4f},
    /* 250 */
    {-0.4f, 0.224f, 2.55f}, {-0.224f, 0.4f, 2.55f}, {0.0f, 0.4f, 2.55f},
    {-1.3f, 0.728f, 2.55f}, {-0.728f, 1.3f, 2.55f}, {0.0f, 1.3f, 2.55f},
    {-1.3f, 0.728f, 2.4f}, {-0.728f, 1.3f, 2.4f}, {0.0f, 1.3f, 2.4f},
    /* 259 */
    {0.224f, 0.4f, 2.55f}, {0.4f, 0.224f, 2.55f}, {0.728f, 1.3f, 2.55f}, {1.3f, 0.728f, 2.55f},
    {0.728f, 1.3f, 2.4f}, {1.3f, 0.728f, 2.4f},
    /* 265: bottom */
    {0.0f, 0.0f, 0.0f}, {1.425f, 0.0f, 0.0f}, {1.425f, 0.798f, 0.0f}, {0.798f, 1.425f, 0.0f},
    {0.0f, 1.425f, 0.0f}, {1.5f, 0.0f, 0.075f}, {1.5f, 0.84f, 0.075f}, {0.84f, 1.5f, 0.075f},
    {0.0f, 1.5f, 0.075f},
    /* 274 */
    {-0.798f, 1.425f, 0.0f}, {-1.425f, 0.798f, 0.0f}, {-1.425f, 0.0f, 0.0f},
    {-0.84f, 1.5f, 0.075f}, {-1.5f, 0.84f, 0.075f}, {-1.5f, 0.0f, 0.075f},
    /* 280 */
    {-1.425f, -0.798f, 0.0f}, {-0.798f, -1.425f, 0.0f}, {0.0f, -1.425f, 0.0f},
    {-1.5f, -0.84f, 0.075f}, {-0.84f, -1.5f, 0.075f}, {0.0f, -1.5f, 0.075f},
    /* 286 */
    {0.798f, -1.425f, 0.0f}, {1.425f, -0.798f, 0.0f}, {0.84f, -1.5f, 0.075f},
    {1.5f, -0.84f, 0.075f},
};

/* Each patch: its 4 x 4 control net, row by row. */
static const uint16_t teapot_patches[TEAPOT_PATCHES][16] = {
    /* rim */
    {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15},
    {3, 16, 17, 18, 7, 19, 20, 21, 11, 22, 23, 24, 15, 25, 26, 27},
    {18, 28, 29, 30, 21, 31, 32, 33, 24, 34, 35, 36, 27, 37, 38, 39},
    {30, 40, 41, 0, 33, 42, 43, 4, 36, 44, 45, 8, 39, 46, 47, 12},
    /* body, upper */
    {12, 13, 14, 15, 48, 49, 50, 51, 52, 53, 54, 55, 56, 57, 58, 59},
    {15, 25, 26, 27, 51, 60, 61, 62, 55, 63, 64, 65, 59, 66, 67, 68},
    {27, 37, 38, 39, 62, 69, 70, 71, 65, 72, 73, 74, 68, 75, 76, 77},
    {39, 46, 47, 12, 71, 78, 79, 48, 74, 80, 81, 52, 77, 82, 83, 56},
    /* body, lower */
    {56, 57, 58, 59, 84, 85, 86, 87, 88, 89, 90, 91, 92, 93, 94, 95},
    {59, 66, 67, 68, 87, 96, 97, 98, 91, 99, 100, 101, 95, 102, 103, 104},
    {68, 75, 76, 77, 98, 105, 106, 107, 101, 108, 109, 110, 104, 111, 112, 113},
    {77, 82, 83, 56, 107, 114, 115, 84, 110, 116, 117, 88, 113, 118, 119, 92},
    /* handle */
    {120, 121, 122, 123, 124, 125, 126, 127, 128, 129, 130, 131, 132, 133, 134, 135},
    {123, 136, 137, 120, 127, 138, 139, 124, 131, 140, 141, 128, 135, 142, 143, 132},
    {132, 133, 134, 135, 144, 145, 146, 147, 148, 149, 150, 151, 68, 152, 153, 154},
    {135, 142, 143, 132, 147, 155, 156, 144, 151, 157, 158, 148, 154, 159, 160, 68},
    /* spout */
    {161, 162, 163, 164, 165, 166, 167, 168, 169, 170, 171, 172, 173, 174, 175, 176},
    {164, 177, 178, 161, 168, 179, 180, 165, 172, 181, 182, 169, 176, 183, 184, 173},
    {173, 174, 175, 176, 185, 186, 187, 188, 189, 190, 191, 192, 193, 194, 195, 196},
    {176, 183, 184, 173, 188, 197, 198, 185, 192, 199, 200, 189, 196, 201, 202, 193},
    /* lid, knob (first row collapsed to the point 203) */
    {203, 203, 203, 203, 204, 205, 206, 207, 208, 208, 208, 208, 209, 210, 211, 212},
    {203, 203, 203, 203, 207, 213, 214, 215, 208, 208, 208, 208, 212, 216, 217, 218},
    {203, 203, 203, 203, 215, 219, 220, 221, 208, 208, 208, 208, 218, 222, 223, 224},
    {203, 203, 203, 203, 221, 225, 226, 204, 208, 208, 208, 208, 224, 227, 228, 209},
    /* lid */
    {209, 210, 211, 212, 229, 230, 231, 232, 233, 234, 235, 236, 237, 238, 239, 240},
    {212, 216, 217, 218, 232, 241, 242, 243, 236, 244, 245, 246, 240, 247, 248, 249},
    {218, 222, 223, 224, 243, 250, 251, 252, 246, 253, 254, 255, 249, 256, 257, 258},
    {224, 227, 228, 209, 252, 259, 260, 229, 255, 261, 262, 233, 258, 263, 264, 237},
    /* bottom (Crow 1987; first row collapsed to the point 265) */
    {265, 265, 265, 265, 266, 267, 268, 269, 270, 271, 272, 273, 92, 119, 118, 113},
    {265, 265, 265, 265, 269, 274, 275, 276, 273, 277, 278, 279, 113, 112, 111, 104},
    {265, 265, 265, 265, 276, 280, 281, 282, 279, 283, 284, 285, 104, 103, 102, 95},
    {265, 265, 265, 265, 282, 286, 287, 266, 285, 288, 289, 270, 95, 94, 93, 92},
};

const float *scene_teapot_control(int patch, int row, int col)
{
    return teapot_points[teapot_patches[patch][4 * row + col]];
}

/*
 * One coordinate of the cubic Bezier curve through p[0..3] at t = k/n.
 * Weights (1-t)^3, 3(1-t)^2 t, 3(1-t) t^2, t^3 from the exact pair
 * a = (n-k)/n, b = k/n; the sum is grouped as (end terms) + (inner terms)
 * and each weight is formed so that swapping a and b swaps w0 with w3 and
 * w1 with w2 bit for bit: the curve evaluated backwards at n-k gives the
 * same double. At k = 0 or n the result is the end point exactly, and four
 * equal points give that point exactly (the collapsed lid and bottom rows).
 */
static double bezier(const double p[4], int k, int n)
{
    if (p[0] == p[1] && p[1] == p[2] && p[2] == p[3]) return p[0];
    double a = (double)(n - k) / n, b = (double)k / n;
    double w0 = a * a * a, w3 = b * b * b;
    double w1 = (a * a) * b * 3.0, w2 = (b * b) * a * 3.0;
    return (w0 * p[0] + w3 * p[3]) + (w1 * p[1] + w2 * p[2]);
}

/* Patch point at grid (i, j): the four rows as curves in t = j/n, then the
 * column through them in s = i/n. */
static dvec3 patch_point(int patch, int i, int j, int n)
{
    double q[3][4];
    for (int r = 0; r < 4; r++) {
        for (int axis = 0; axis < 3; axis++) {
            double p[4];
            for (int c = 0; c < 4; c++) p[c] = scene_teapot_control(patch, r, c)[axis];
            q[axis][r] = bezier(p, j, n);
        }
    }
    dvec3 v = {bezier(q[0], i, n), bezier(q[1], i, n), bezier(q[2], i, n)};
    return v;
}

uint64_t scene_teapot_tri_count(int n)
{
    return 64ull * (uint64_t)n * (uint64_t)n - 8ull * (uint64_t)n;
}

/* Patches whose first control row is one point (the lid knob, the bottom centre). */
static int patch_collapsed(int patch)
{
    const uint16_t *row = teapot_patches[patch];
    return row[0] == row[1] && row[1] == row[2] && row[2] == row[3];
}

int scene_teapot_add(scene_builder *b, int n, accel_error *err)
{
    if (n < 1 || n > 65535)
        return accel_fail(err, ACCEL_ERR_RANGE, "teapot: %d divisions per patch (1..65535)", n);
    size_t side = (size_t)n + 1;
    if (side > SIZE_MAX / side / sizeof(vec3))
        return accel_fail(err, ACCEL_ERR_RANGE, "teapot: %d divisions per patch is too many", n);
    int rc = scene_check_count("teapot", scene_teapot_tri_count(n), err);
    if (rc == 0) rc = scene_builder_reserve_tris(b, (size_t)scene_teapot_tri_count(n), err);
    if (rc) return rc;
    vec3 *grid = malloc(side * side * sizeof *grid);
    if (!grid) return accel_fail(err, ACCEL_ERR_NOMEM, "teapot: out of memory (%d divisions)", n);
    for (int patch = 0; patch < TEAPOT_PATCHES && rc == 0; patch++) {
        int collapsed = patch_collapsed(patch);
        for (int i = 0; i <= n; i++)
            for (int j = 0; j <= n; j++)
                grid[(size_t)i * side + j] = dvec3_to_float(patch_point(patch, i, j, n));
        for (int i = 0; i < n && rc == 0; i++) {
            for (int j = 0; j < n && rc == 0; j++) {
                /* Quad corners in the SPD order: (s,t), (s,t+1), (s+1,t+1), (s+1,t). */
                const vec3 *row0 = grid + (size_t)i * side, *row1 = row0 + side;
                vec3 q[4] = {row0[j], row0[j + 1], row1[j + 1], row1[j]};
                /* The first triangle of a square on a collapsed row has two
                 * corners at the collapsed point: it is left out. */
                if (!(i == 0 && collapsed)) rc = scene_builder_add_tri(b, q[0], q[1], q[2], err);
                if (rc == 0) rc = scene_builder_add_tri(b, q[2], q[3], q[0], err);
            }
        }
    }
    free(grid);
    return rc;
}
