/*
 * shade.c - a shaded picture of closest hits (bin/trace --image): the
 * cosine to the viewer and a Lambert term towards the scene's light, grey
 * triangles and orange spheres, dark blue for misses.
 */
#include <math.h>

#include "image/shade.h"

void image_shade(const accel_scene *s, const rays_set *r, const accel_hit *hits, image_rgb *img)
{
    for (size_t i = 0; i < r->count; i++) {
        uint32_t px = r->pixel ? r->pixel[i] : (uint32_t)i;
        if (px >= (uint32_t)(img->width * img->height)) continue;
        uint8_t *c = img->rgb + 3 * (size_t)px;
        vec3 p, n;
        if (!rays_hit_frame(s, &r->rays[i], &hits[i], &p, &n)) {
            c[0] = 30, c[1] = 34, c[2] = 48;
            continue;
        }
        vec3 d = v3_norm(v3(r->rays[i].dx, r->rays[i].dy, r->rays[i].dz));
        vec3 l = v3_norm(v3_sub(s->light, p));
        float head = fabsf(v3_dot(n, d));
        float lamb = fmaxf(0.0f, v3_dot(n, l));
        float k = 0.15f + 0.45f * head + 0.4f * lamb;
        float base[3] = {0.85f, 0.85f, 0.9f};
        if (hits[i].prim >= s->tri_count) base[0] = 0.95f, base[1] = 0.75f, base[2] = 0.55f;
        for (int j = 0; j < 3; j++) c[j] = (uint8_t)fminf(255.0f, 255.0f * k * base[j]);
    }
}
