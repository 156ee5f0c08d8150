/* Embedding ember from C (docs/embedding.md): build a scene from arrays, render it
 * once with this program's own ray tracer (two callbacks over the same arrays) and once
 * with ember's built-in BVH, check that the two images agree, and write both as PFM.
 * Then never lose a render: half the BVH's passes, exported as bytes, imported into a
 * new renderer and continued give the BVH's image bit for bit (seen to fail with the
 * continued passes numbered from 0, 36 passes held, and with the image of the passes
 * since the import only, other bits). And the same tracer answering batches of rays
 * (`EmberRayBatchCallbacks`) gives PT's bits of one ray per call.
 *
 *   render OUTPUT_PREFIX      (writes OUTPUT_PREFIX-callbacks.pfm, -bvh.pfm)
 *
 * Built and run under AddressSanitizer and UBSan by scripts/test-capi.sh. */
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ember.h"
#include "tracer.h"

#define CHECK(call)                                                               \
    do {                                                                          \
        EmberStatus s_ = (call);                                                  \
        if (s_ != EMBER_STATUS_OK) {                                              \
            fprintf(stderr, "%s failed (%d): %s\n", #call, (int)s_, ember_last_error()); \
            exit(1);                                                              \
        }                                                                         \
    } while (0)

/* A closed box (floor, ceiling, three walls) with a light on the ceiling and a glass-free
 * block: 8 quads of 2 triangles. */
static const float POSITIONS[] = {
    /* each quad counter-clockwise seen from inside the box (its emitting, lit side) */
    -1, 0, -1, -1, 0, 1, 1, 0, 1, 1, 0, -1,          /* floor 0-3 */
    -1, 2, -1, 1, 2, -1, 1, 2, 1, -1, 2, 1,          /* ceiling 4-7 */
    -1, 0, -1, 1, 0, -1, 1, 2, -1, -1, 2, -1,        /* back 8-11 */
    -1, 0, -1, -1, 2, -1, -1, 2, 1, -1, 0, 1,        /* left 12-15 */
    1, 0, -1, 1, 0, 1, 1, 2, 1, 1, 2, -1,            /* right 16-19 */
    -0.3f, 1.99f, -0.3f, 0.3f, 1.99f, -0.3f, 0.3f, 1.99f, 0.3f, -0.3f, 1.99f, 0.3f, /* light 20-23, facing down */
    -0.5f, 0.6f, -0.4f, -0.5f, 0.6f, 0.2f, 0.1f, 0.6f, 0.2f, 0.1f, 0.6f, -0.4f,     /* block top 24-27 */
    -0.5f, 0, 0.2f, 0.1f, 0, 0.2f, 0.1f, 0.6f, 0.2f, -0.5f, 0.6f, 0.2f,            /* block front 28-31 */
};
#define QUADS 8
static uint32_t indices[QUADS * 6];
static uint32_t tri_materials[QUADS * 2];
static float tri_emission[QUADS * 2 * 3];

static void build_arrays(void) {
    for (uint32_t q = 0; q < QUADS; q++) {
        uint32_t b = 4 * q;
        uint32_t t[6] = {b, b + 1, b + 2, b, b + 2, b + 3};
        memcpy(&indices[6 * q], t, sizeof t);
        /* 0 white, 1 red (left), 2 green (right), 3 black light base */
        uint32_t m = q == 3 ? 1 : q == 4 ? 2 : q == 5 ? 3 : 0;
        tri_materials[2 * q] = tri_materials[2 * q + 1] = m;
        for (int k = 0; k < 6; k++) tri_emission[6 * q + k] = q == 5 ? 12.0f : 0.0f;
    }
}

/* The same tracer answering batches (rays in arrays, `ember_renderer_create_batched`). */
static void my_intersect_batch(void *user, const EmberRayBatch *rays, EmberHit *hits, bool *found) {
    for (uint32_t i = 0; i < rays->count; i++) {
        EmberRay r = {{rays->origin_x[i], rays->origin_y[i], rays->origin_z[i]},
                      {rays->dir_x[i], rays->dir_y[i], rays->dir_z[i]}, rays->t_max[i]};
        found[i] = my_intersect(user, &r, &hits[i]);
    }
}

static void my_occluded_batch(void *user, const EmberRayBatch *rays, bool *occluded) {
    for (uint32_t i = 0; i < rays->count; i++) {
        EmberRay r = {{rays->origin_x[i], rays->origin_y[i], rays->origin_z[i]},
                      {rays->dir_x[i], rays->dir_y[i], rays->dir_z[i]}, rays->t_max[i]};
        occluded[i] = my_occluded(user, &r);
    }
}

static void write_pfm(const char *path, const float *rgb, uint32_t w, uint32_t h) {
    FILE *f = fopen(path, "wb");
    if (!f) { perror(path); exit(1); }
    fprintf(f, "PF\n%u %u\n-1.0\n", w, h);
    /* PFM rows run bottom to top. */
    for (uint32_t y = 0; y < h; y++) fwrite(&rgb[3 * (size_t)w * (h - 1 - y)], sizeof(float), 3 * (size_t)w, f);
    fclose(f);
}

#define PASSES 24
static const EmberRenderSettings SETTINGS = {.estimator = "bdpt", .seed = 7, .max_depth = 6, .threads = 2};

static float *render(EmberScene scene, const EmberRayCallbacks *callbacks, uint32_t *w, uint32_t *h) {
    EmberRenderer r;
    CHECK(ember_renderer_create(scene, &SETTINGS, callbacks, &r));
    CHECK(ember_render_passes(r, PASSES));
    CHECK(ember_renderer_size(r, w, h));
    size_t n = 3 * (size_t)*w * *h;
    float *rgb = malloc(n * sizeof *rgb);
    CHECK(ember_renderer_image(r, rgb, n));
    CHECK(ember_renderer_destroy(r));
    return rgb;
}

/* PT through the program's tracer one ray per call and 16 rays per call: the same bits
 * (the renderer keeps 16 paths in flight for the batches; the image does not depend on
 * it). */
static bool batches_match(EmberScene scene, Mesh *mesh) {
    static const EmberRenderSettings PT = {.estimator = "pt", .seed = 3, .max_depth = 6, .threads = 2};
    EmberRayCallbacks single = {.user_data = mesh, .intersect = my_intersect, .occluded = my_occluded};
    EmberRayBatchCallbacks batch = {.user_data = mesh, .width = 16, .intersect = my_intersect_batch, .occluded = my_occluded_batch};
    EmberRenderer a, b;
    CHECK(ember_renderer_create(scene, &PT, &single, &a));
    CHECK(ember_renderer_create_batched(scene, &PT, &batch, &b));
    CHECK(ember_render_passes(a, 4));
    CHECK(ember_render_passes(b, 4));
    uint32_t w, h;
    CHECK(ember_renderer_size(a, &w, &h));
    size_t n = 3 * (size_t)w * h;
    float *ia = malloc(n * sizeof *ia), *ib = malloc(n * sizeof *ib);
    CHECK(ember_renderer_image(a, ia, n));
    CHECK(ember_renderer_image(b, ib, n));
    bool same = memcmp(ia, ib, n * sizeof *ia) == 0;
    free(ia);
    free(ib);
    CHECK(ember_renderer_destroy(a));
    CHECK(ember_renderer_destroy(b));
    printf("PT with batch callbacks (16 rays per call): %s\n", same ? "the same bits as one ray per call" : "DIFFERENT bits");
    return same;
}

/* The built-in BVH's render again, interrupted halfway: its film exported (the size,
 * then the bytes; an engine would write them to a file), the renderer destroyed, and
 * the film imported into a new renderer that renders the other half. */
static float *render_continued(EmberScene scene, size_t floats) {
    EmberRenderer first, second;
    CHECK(ember_renderer_create(scene, &SETTINGS, NULL, &first));
    CHECK(ember_render_passes(first, PASSES / 2));
    size_t size, written;
    CHECK(ember_film_export(first, NULL, 0, &size));
    uint8_t *bytes = malloc(size);
    CHECK(ember_film_export(first, bytes, size, &written));
    CHECK(ember_renderer_destroy(first));
    CHECK(ember_renderer_create(scene, &SETTINGS, NULL, &second));
    CHECK(ember_film_import(second, bytes, written));
    free(bytes);
    CHECK(ember_render_passes(second, PASSES - PASSES / 2));
    uint32_t passes;
    CHECK(ember_renderer_passes(second, &passes));
    if (passes != PASSES) { fprintf(stderr, "the continued render holds %u passes, not %d\n", passes, PASSES); exit(1); }
    float *rgb = malloc(floats * sizeof *rgb);
    CHECK(ember_renderer_image(second, rgb, floats));
    CHECK(ember_renderer_destroy(second));
    printf("film export: %zu bytes after %d passes, continued for %d\n", size, PASSES / 2, PASSES - PASSES / 2);
    return rgb;
}

int main(int argc, char **argv) {
    if (argc != 2) { fprintf(stderr, "usage: %s OUTPUT_PREFIX\n", argv[0]); return 2; }
    printf("%s\n", ember_version());
    build_arrays();
    EmberMaterial materials[4] = {
        {.kind = EMBER_MATERIAL_KIND_DIFFUSE, .color = {0.75f, 0.75f, 0.75f}},
        {.kind = EMBER_MATERIAL_KIND_DIFFUSE, .color = {0.7f, 0.1f, 0.1f}},
        {.kind = EMBER_MATERIAL_KIND_DIFFUSE, .color = {0.1f, 0.7f, 0.1f}},
        {.kind = EMBER_MATERIAL_KIND_DIFFUSE, .color = {0.0f, 0.0f, 0.0f}},
    };
    EmberSceneDesc desc = {
        .positions = POSITIONS, .vertex_count = sizeof POSITIONS / sizeof POSITIONS[0] / 3,
        .indices = indices, .triangle_count = QUADS * 2,
        .triangle_materials = tri_materials, .triangle_emission = tri_emission,
        .materials = materials, .material_count = 4,
        .camera = {.origin = {0, 1, 3.4f}, .target = {0, 1, 0}, .up = {0, 1, 0}, .fov_degrees = 40, .width = 48, .height = 40},
    };
    EmberScene scene;
    CHECK(ember_scene_create(&desc, &scene));
    Mesh mesh = {POSITIONS, indices, QUADS * 2};
    EmberRayCallbacks callbacks = {.user_data = &mesh, .intersect = my_intersect, .occluded = my_occluded};

    uint32_t w, h;
    float *mine = render(scene, &callbacks, &w, &h);
    float *bvh = render(scene, NULL, &w, &h);
    float *continued = render_continued(scene, 3 * (size_t)w * h);
    bool batches = batches_match(scene, &mesh);
    CHECK(ember_scene_destroy(scene));
    if (!batches) {
        fprintf(stderr, "batch callbacks gave other bits than single-ray callbacks\n");
        return 1;
    }
    bool same = memcmp(continued, bvh, 3 * (size_t)w * h * sizeof *bvh) == 0;
    free(continued);
    if (!same) {
        fprintf(stderr, "the render exported, imported and continued differs from the one render\n");
        return 1;
    }

    /* The two tracers find the same surfaces; the images are two estimates of one image
     * (same seed, tracers rounding differently): compare per 8x8 block, in the mean. */
    double worst = 0.0, total_a = 0.0, total_b = 0.0;
    for (uint32_t by = 0; by + 8 <= h; by += 8) {
        for (uint32_t bx = 0; bx + 8 <= w; bx += 8) {
            double a = 0, b = 0;
            for (uint32_t y = by; y < by + 8; y++)
                for (uint32_t x = bx; x < bx + 8; x++)
                    for (int c = 0; c < 3; c++) { a += mine[3 * (y * w + x) + c]; b += bvh[3 * (y * w + x) + c]; }
            total_a += a; total_b += b;
            if (b > 1e-3) { double d = fabs(a / b - 1.0); if (d > worst) worst = d; }
        }
    }
    printf("callback tracer / BVH: image mean ratio %.4f, worst 8x8 block %.1f %%\n", total_a / total_b, 100.0 * worst);
    char path[4096];
    snprintf(path, sizeof path, "%s-callbacks.pfm", argv[1]);
    write_pfm(path, mine, w, h);
    snprintf(path, sizeof path, "%s-bvh.pfm", argv[1]);
    write_pfm(path, bvh, w, h);
    free(mine);
    free(bvh);
    if (!(total_b > 0.0 && fabs(total_a / total_b - 1.0) < 0.03 && worst < 0.25)) {
        fprintf(stderr, "the callback tracer's image disagrees with the BVH's\n");
        return 1;
    }
    printf("wrote %s-callbacks.pfm and %s-bvh.pfm\n", argv[1], argv[1]);
    return 0;
}
