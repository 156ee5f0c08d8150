/* The complete scene description from C (`EmberSceneDesc2`, docs/embedding.md): a floor
 * of textured rough plastic (a pixel array on per-vertex texture coordinates tiling it,
 * tilted per-vertex normals), a wall with a checkerboard, an environment map given as
 * pixels, a thin lens, a tent filter and a vertical field of view. Renders it with PT on
 * the built-in BVH and on this program's own tracer (tracer.h: ember rebuilds the
 * normals and texture coordinates of a hit from its copy of the arrays), checks that
 * the two agree per 8x8 block, and writes, for scripts/test-capi.sh to render with
 * `ember render` and compare bit for bit:
 *
 *   scene2 DIR     DIR/c.pfm (the BVH's image), DIR/scene.xml with DIR/floor.obj,
 *                  DIR/wall.obj, DIR/albedo.pfm, DIR/sky.pfm (the same scene in XML)
 *
 * Built and run under AddressSanitizer and UBSan by scripts/test-capi.sh. Seen to fail
 * there (run once, reverted) with the library handing texture coordinates to the core
 * as (v, u): 1607 of 1728 pixels differ from `ember render`'s. */
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

/* The render the script repeats with `ember render` (docs/embedding.md). */
#define W 48
#define H 36
#define PASSES 4
#define SEED 5
static const EmberRenderSettings PT = {.estimator = "pt", .seed = SEED, .max_depth = -1, .threads = 2};

/* Two quads of two triangles: the floor (vertices 0-3) and the back wall (4-7). */
static const float POSITIONS[] = {
    -3, -1, 0.5f, -3, -1, 6, 3, -1, 6, 3, -1, 0.5f, /* floor, facing up */
    -3, -1, 6, -3, 3, 6, 3, 3, 6, 3, -1, 6,         /* wall, facing the camera */
};
static const float NORMALS[] = {
    0.1f, 1, 0, -0.1f, 1, 0.05f, 0, 0.9f, -0.1f, 0.2f, 1, 0.1f, /* not normalised: ember does it */
    0, 0, -1, 0, 0, -1, 0, 0, -1, 0, 0, -1,
};
static const float UVS[] = {0, 0, 0, 3, 3, 3, 3, 0, /* the albedo tiled 3 x 3 */ 0, 0, 0, 1, 1, 1, 1, 0};
static const uint32_t INDICES[] = {0, 1, 2, 0, 2, 3, 4, 5, 6, 4, 6, 7};
static const uint32_t TRI_MATERIALS[] = {0, 0, 1, 1};
#define VERTICES 8
#define TRIANGLES 4

#define ALBEDO_W 4
#define ALBEDO_H 4
#define SKY_W 16
#define SKY_H 8
static float albedo[ALBEDO_W * ALBEDO_H * 3];
static float sky[SKY_W * SKY_H * 3];

static void fill_images(void) {
    for (int i = 0; i < ALBEDO_W * ALBEDO_H; i++) {
        albedo[3 * i] = 0.15f + 0.05f * (float)i;
        albedo[3 * i + 1] = 0.8f - 0.04f * (float)i;
        albedo[3 * i + 2] = 0.3f + 0.1f * (float)(i % 5);
    }
    for (int y = 0; y < SKY_H; y++)
        for (int x = 0; x < SKY_W; x++) {
            float *p = &sky[3 * (y * SKY_W + x)];
            bool sun = x == 5 && y == 2;
            p[0] = sun ? 40.0f : 0.3f + 0.05f * (float)y;
            p[1] = sun ? 36.0f : 0.4f + 0.02f * (float)x;
            p[2] = sun ? 30.0f : 0.8f - 0.07f * (float)y;
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

static FILE *open_in(const char *dir, const char *name) {
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE *f = fopen(path, "w");
    if (!f) { perror(path); exit(1); }
    return f;
}

/* %.17g of the float as a double: the reader parses in double precision, so it reads
 * exactly this float (and normalises directions from it as ember_scene_create2 does). */
#define F(x) ((double)(x))

static void write_obj(const char *dir, const char *name, int first) {
    FILE *f = open_in(dir, name);
    for (int v = first; v < first + 4; v++) fprintf(f, "v %.17g %.17g %.17g\n", F(POSITIONS[3 * v]), F(POSITIONS[3 * v + 1]), F(POSITIONS[3 * v + 2]));
    for (int v = first; v < first + 4; v++) fprintf(f, "vt %.17g %.17g\n", F(UVS[2 * v]), F(UVS[2 * v + 1]));
    for (int v = first; v < first + 4; v++) fprintf(f, "vn %.17g %.17g %.17g\n", F(NORMALS[3 * v]), F(NORMALS[3 * v + 1]), F(NORMALS[3 * v + 2]));
    fprintf(f, "f 1/1/1 2/2/2 3/3/3\nf 1/1/1 3/3/3 4/4/4\n");
    fclose(f);
}

/* The scene in Mitsuba 3's XML, parameter for parameter. */
static void write_xml(const char *dir, const EmberSceneDesc2 *d, const EmberBsdf *plastic, const EmberTexture *checker, const EmberLight *env) {
    char path[4096];
    write_obj(dir, "floor.obj", 0);
    write_obj(dir, "wall.obj", 4);
    snprintf(path, sizeof path, "%s/albedo.pfm", dir);
    write_pfm(path, albedo, ALBEDO_W, ALBEDO_H);
    snprintf(path, sizeof path, "%s/sky.pfm", dir);
    write_pfm(path, sky, SKY_W, SKY_H);
    FILE *f = open_in(dir, "scene.xml");
    const EmberCamera *c = &d->camera;
    fprintf(f, "<scene version=\"3.0.0\">\n  <sensor type=\"thinlens\">\n");
    fprintf(f, "    <float name=\"fov\" value=\"%.17g\"/><string name=\"fov_axis\" value=\"y\"/>\n", F(c->fov_degrees));
    fprintf(f, "    <float name=\"aperture_radius\" value=\"%.17g\"/><float name=\"focus_distance\" value=\"%.17g\"/>\n", F(d->lens.aperture_radius),
            F(d->lens.focus_distance));
    fprintf(f, "    <transform name=\"to_world\"><lookat origin=\"0, 0, 0\" target=\"%.17g, %.17g, %.17g\" up=\"0, 1, 0\"/></transform>\n", F(c->target[0]),
            F(c->target[1]), F(c->target[2]));
    fprintf(f, "    <film type=\"hdrfilm\"><integer name=\"width\" value=\"%u\"/><integer name=\"height\" value=\"%u\"/>\n", c->width, c->height);
    fprintf(f, "      <rfilter type=\"tent\"><float name=\"radius\" value=\"%.17g\"/></rfilter></film>\n  </sensor>\n", F(d->filter.radius));
    fprintf(f, "  <bsdf type=\"roughplastic\" id=\"floor\"><string name=\"distribution\" value=\"ggx\"/><float name=\"alpha\" value=\"%.17g\"/>\n",
            F(plastic->alpha));
    fprintf(f, "    <texture type=\"bitmap\" name=\"diffuse_reflectance\"><string name=\"filename\" value=\"albedo.pfm\"/></texture></bsdf>\n");
    fprintf(f, "  <bsdf type=\"diffuse\" id=\"wall\"><texture type=\"checkerboard\" name=\"reflectance\">\n");
    fprintf(f, "    <rgb name=\"color0\" value=\"%.17g, %.17g, %.17g\"/><rgb name=\"color1\" value=\"%.17g, %.17g, %.17g\"/>\n", F(checker->color0[0]),
            F(checker->color0[1]), F(checker->color0[2]), F(checker->color1[0]), F(checker->color1[1]), F(checker->color1[2]));
    fprintf(f, "    <transform name=\"to_uv\"><scale x=\"%.17g\" y=\"%.17g\"/></transform></texture></bsdf>\n", F(checker->to_uv[0]), F(checker->to_uv[4]));
    for (int s = 0; s < 2; s++)
        fprintf(f, "  <shape type=\"obj\"><string name=\"filename\" value=\"%s.obj\"/><boolean name=\"flip_tex_coords\" value=\"false\"/><ref id=\"%s\"/></shape>\n",
                s ? "wall" : "floor", s ? "wall" : "floor");
    fprintf(f, "  <emitter type=\"envmap\"><string name=\"filename\" value=\"sky.pfm\"/><float name=\"scale\" value=\"%.17g\"/>\n", F(env->scale));
    fprintf(f, "    <transform name=\"to_world\"><matrix value=\"");
    for (int r = 0; r < 3; r++) fprintf(f, "%.17g %.17g %.17g 0 ", F(env->to_world[r][0]), F(env->to_world[r][1]), F(env->to_world[r][2]));
    fprintf(f, "0 0 0 1\"/></transform></emitter>\n</scene>\n");
    fclose(f);
}

static float *render(EmberScene scene, const EmberRayCallbacks *callbacks) {
    EmberRenderer r;
    CHECK(ember_renderer_create(scene, &PT, callbacks, &r));
    CHECK(ember_render_passes(r, PASSES / 2));
    CHECK(ember_render_passes(r, PASSES - PASSES / 2)); /* the renderer's threads again */
    float *rgb = malloc(3 * (size_t)W * H * sizeof *rgb);
    CHECK(ember_renderer_image(r, rgb, 3 * (size_t)W * H));
    CHECK(ember_renderer_destroy(r));
    return rgb;
}

int main(int argc, char **argv) {
    if (argc != 2) { fprintf(stderr, "usage: %s DIR\n", argv[0]); return 2; }
    fill_images();
    EmberBsdf materials[2];
    CHECK(ember_bsdf_init(EMBER_BSDF_KIND_ROUGH_PLASTIC, &materials[0]));
    materials[0].distribution = EMBER_MICROFACET_GGX;
    materials[0].alpha = 0.2f;
    materials[0].textures[EMBER_TEXTURE_SLOT_DIFFUSE] = 0;
    CHECK(ember_bsdf_init(EMBER_BSDF_KIND_DIFFUSE, &materials[1]));
    materials[1].textures[EMBER_TEXTURE_SLOT_DIFFUSE] = 1;
    EmberTexture textures[3];
    CHECK(ember_texture_init(EMBER_TEXTURE_KIND_BITMAP, &textures[0]));
    textures[0].pixels = albedo, textures[0].width = ALBEDO_W, textures[0].height = ALBEDO_H;
    CHECK(ember_texture_init(EMBER_TEXTURE_KIND_CHECKERBOARD, &textures[1]));
    const float c0[3] = {0.7f, 0.2f, 0.1f}, c1[3] = {0.1f, 0.3f, 0.6f};
    memcpy(textures[1].color0, c0, sizeof c0);
    memcpy(textures[1].color1, c1, sizeof c1);
    textures[1].to_uv[0] = textures[1].to_uv[4] = 4.0f;
    CHECK(ember_texture_init(EMBER_TEXTURE_KIND_BITMAP, &textures[2]));
    textures[2].pixels = sky, textures[2].width = SKY_W, textures[2].height = SKY_H;
    EmberLight env;
    CHECK(ember_light_init(EMBER_LIGHT_KIND_ENVMAP, &env));
    env.texture = 2, env.scale = 1.5f;
    /* A quarter turn about +y, row-major. */
    const float rotation[3][3] = {{0, 0, 1}, {0, 1, 0}, {-1, 0, 0}};
    memcpy(env.to_world, rotation, sizeof rotation);
    EmberSceneDesc2 desc = {
        .positions = POSITIONS, .vertex_count = VERTICES, .normals = NORMALS, .uvs = UVS,
        .indices = INDICES, .triangle_count = TRIANGLES, .triangle_materials = TRI_MATERIALS,
        .materials = materials, .material_count = 2, .textures = textures, .texture_count = 3,
        .lights = &env, .light_count = 1,
        .camera = {.origin = {0, 0, 0}, .target = {0.1f, -0.25f, 1}, .up = {0, 1, 0}, .fov_degrees = 50, .width = W, .height = H},
        .fov_axis = EMBER_FOV_AXIS_Y,
        .lens = {.aperture_radius = 0.04f, .focus_distance = 3},
        .filter = {.kind = EMBER_FILTER_KIND_TENT, .radius = 1.25f},
    };
    EmberScene scene;
    CHECK(ember_scene_create2(&desc, &scene));
    Mesh mesh = {POSITIONS, INDICES, TRIANGLES};
    EmberRayCallbacks callbacks = {.user_data = &mesh, .intersect = my_intersect, .occluded = my_occluded};
    float *bvh = render(scene, NULL);
    float *mine = render(scene, &callbacks);
    CHECK(ember_scene_destroy(scene));

    /* Two estimates of one image (the tracers round differently): per 8x8 block. */
    double worst = 0.0, total_a = 0.0, total_b = 0.0;
    for (uint32_t by = 0; by + 8 <= H; by += 8)
        for (uint32_t bx = 0; bx + 8 <= W; bx += 8) {
            double a = 0, b = 0;
            for (uint32_t y = by; y < by + 8; y++)
                for (uint32_t x = bx; x < bx + 8; x++)
                    for (int c = 0; c < 3; c++) { a += mine[3 * (y * W + x) + c]; b += bvh[3 * (y * W + x) + c]; }
            total_a += a, total_b += b;
            if (b > 1e-3) { double d = fabs(a / b - 1.0); if (d > worst) worst = d; }
        }
    printf("scene2: callback tracer / BVH: image mean %.4f, ratio %.4f, worst 8x8 block %.1f %%\n", total_b / (3.0 * W * H), total_a / total_b,
           100.0 * worst);
    char path[4096];
    snprintf(path, sizeof path, "%s/c.pfm", argv[1]);
    write_pfm(path, bvh, W, H);
    write_xml(argv[1], &desc, &materials[0], &textures[1], &env);
    free(mine);
    free(bvh);
    if (!(total_b > 0.05 * 3.0 * W * H && fabs(total_a / total_b - 1.0) < 0.03 && worst < 0.25)) {
        fprintf(stderr, "scene2: the callback tracer's image disagrees with the BVH's (or is black)\n");
        return 1;
    }
    printf("scene2: wrote %s/c.pfm and %s/scene.xml\n", argv[1], argv[1]);
    return 0;
}
