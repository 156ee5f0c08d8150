/* The C examples' own ray tracer (render.c, scene2.c): Möller–Trumbore over every
 * triangle of the description's arrays, answering ember's callbacks by triangle index
 * and barycentrics. */
#ifndef EMBER_EXAMPLE_TRACER_H
#define EMBER_EXAMPLE_TRACER_H

#include <stdbool.h>
#include <stdint.h>

#include "ember.h"

typedef struct {
    const float *p;
    const uint32_t *idx;
    uint32_t n;
} Mesh;

static bool hit_triangle(const Mesh *m, uint32_t t, const EmberRay *r, float tmax, float *tt, float *b1, float *b2) {
    const float *a = &m->p[3 * m->idx[3 * t]], *b = &m->p[3 * m->idx[3 * t + 1]], *c = &m->p[3 * m->idx[3 * t + 2]];
    double e1[3], e2[3], h[3], s[3], q[3];
    for (int i = 0; i < 3; i++) { e1[i] = b[i] - a[i]; e2[i] = c[i] - a[i]; s[i] = r->origin[i] - a[i]; }
    h[0] = r->dir[1] * e2[2] - r->dir[2] * e2[1];
    h[1] = r->dir[2] * e2[0] - r->dir[0] * e2[2];
    h[2] = r->dir[0] * e2[1] - r->dir[1] * e2[0];
    double det = e1[0] * h[0] + e1[1] * h[1] + e1[2] * h[2];
    if (det == 0.0) return false;
    double inv = 1.0 / det;
    double u = inv * (s[0] * h[0] + s[1] * h[1] + s[2] * h[2]);
    if (u < 0.0 || u > 1.0) return false;
    q[0] = s[1] * e1[2] - s[2] * e1[1];
    q[1] = s[2] * e1[0] - s[0] * e1[2];
    q[2] = s[0] * e1[1] - s[1] * e1[0];
    double v = inv * (r->dir[0] * q[0] + r->dir[1] * q[1] + r->dir[2] * q[2]);
    if (v < 0.0 || u + v > 1.0) return false;
    double d = inv * (e2[0] * q[0] + e2[1] * q[1] + e2[2] * q[2]);
    if (!(d > 0.0 && d < tmax)) return false;
    *tt = (float)d; *b1 = (float)u; *b2 = (float)v;
    return (*tt > 0.0f && *tt < tmax);
}

static bool my_intersect(void *user, const EmberRay *ray, EmberHit *hit) {
    const Mesh *m = user;
    float best = ray->t_max;
    bool found = false;
    for (uint32_t t = 0; t < m->n; t++) {
        float tt, b1, b2;
        if (hit_triangle(m, t, ray, best, &tt, &b1, &b2)) {
            best = tt; found = true;
            hit->t = tt; hit->primitive = t; hit->b1 = b1; hit->b2 = b2;
        }
    }
    return found;
}

static bool my_occluded(void *user, const EmberRay *ray) {
    const Mesh *m = user;
    for (uint32_t t = 0; t < m->n; t++) {
        float tt, b1, b2;
        if (hit_triangle(m, t, ray, ray->t_max, &tt, &b1, &b2)) return true;
    }
    return false;
}

#endif
