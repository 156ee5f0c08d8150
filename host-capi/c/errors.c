/* Every error path of the C API, table-driven: each row makes one bad call and names
 * the status and a fragment of the message it must give. Null pointers, bad counts and
 * indices, an enum value out of range, destroyed and reused handles, invalid
 * configuration values, renders too large for memory, calls out of order, and ray
 * callbacks returning hits that break their contract. Built and run under
 * AddressSanitizer and UBSan by scripts/test-capi.sh.
 *
 * Hostile input (issue 51), each row seen to fail with its bug injected:
 * - "material kind 3": with the kind check removed (an unknown kind taken as diffuse,
 *   as the unchecked enum read happened to), status OK.
 * - "camera 65536x65536": without the memory check (crate::check_memory not called),
 *   the program aborted ("allocator is out of memory trying to allocate 0x3000000000
 *   bytes", the film's sums).
 * - "memory-limit below the film", "light paths past memory-limit": with the option
 *   parsed but not passed to the check, status OK.
 * - "threads UINT32_MAX": without the cap (threads taken as given), the program
 *   aborted after 14 minutes under ASan, which ran out of mappings for the threads'
 *   shadow memory (without ASan: a failed call after ~30 s and 240 MB).
 * - "callback barycentrics outside the triangle": with the check for finite values
 *   only (as before), status OK.
 * - "callback error mapping a chunk": with ember_phase_map not looking at the fault,
 *   status OK. Before issue 51 the other "callback" rows returned
 *   EMBER_STATUS_PANIC and printed the panic on stderr; they now return
 *   EMBER_STATUS_CALLBACK_ERROR.
 *
 * Films (issue 50), each "film" row seen to fail with its check removed: status OK
 * for the damaged byte (checksum), seed, max depth, tracer, scene, capacity (the export
 * then wrote 3230 bytes into 16), import after a pass, pass start after an import and
 * export out of order; the next check's message instead for the truncated buffer
 * ("checksum"), another estimator ("configuration"), another size ("scene") and a
 * non-film ("format version"); an ASan SEGV for the null bytes and written. */
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <string.h>

#include "ember.h"

static const float P[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
static const uint32_t IDX[] = {0, 1, 2, 0, 2, 3};
static const uint32_t MAT[] = {0, 0};
static const float EMIT[] = {0, 0, 0, 5, 5, 5};
static const EmberMaterial MATERIALS[] = {{.kind = EMBER_MATERIAL_KIND_DIFFUSE, .color = {0.5f, 0.5f, 0.5f}}};

static EmberSceneDesc good_desc(void) {
    EmberSceneDesc d = {
        .positions = P, .vertex_count = 4, .indices = IDX, .triangle_count = 2,
        .triangle_materials = MAT, .triangle_emission = EMIT,
        .materials = MATERIALS, .material_count = 1,
        .camera = {.origin = {2, 2, 2}, .target = {0, 0, 0}, .up = {0, 1, 0}, .fov_degrees = 45, .width = 8, .height = 8},
    };
    return d;
}

static EmberScene scene;          /* a live scene */
static EmberScene dead_scene;     /* destroyed */
static EmberRenderer renderer;    /* a live renderer (pt) */
static EmberRenderer dead_renderer;

static EmberStatus create(EmberSceneDesc d) { EmberScene s; return ember_scene_create(&d, &s); }
static EmberStatus settings_with(EmberRenderSettings st) { EmberRenderer r; return ember_renderer_create(scene, &st, NULL, &r); }
static EmberRenderSettings pt(void) { EmberRenderSettings s = {.estimator = "pt", .seed = 1, .max_depth = 4, .threads = 1}; return s; }

/* A tracer that answers every ray with the same hit (t: at most 1, inside t_max). */
typedef struct { float t; uint32_t primitive; float b1, b2; } FixedHit;
static bool fixed_intersect(void *u, const EmberRay *ray, EmberHit *hit) {
    const FixedHit *f = u;
    hit->t = isnan(f->t) ? f->t : fminf(f->t, ray->t_max * 0.5f); hit->primitive = f->primitive; hit->b1 = f->b1; hit->b2 = f->b2;
    return true;
}
static bool never(void *u, const EmberRay *ray) { (void)u; (void)ray; return false; }

/* Objects a case made, destroyed after its status and message are read. */
static EmberRenderer case_renderer;
static EmberScene case_scene;

/* Each case: a call returning a status. */
static EmberStatus c_desc_null(void) { EmberScene s; return ember_scene_create(NULL, &s); }
static EmberStatus c_out_null(void) { EmberSceneDesc d = good_desc(); return ember_scene_create(&d, NULL); }
static EmberStatus c_positions_null(void) { EmberSceneDesc d = good_desc(); d.positions = NULL; return create(d); }
static EmberStatus c_index_past(void) { EmberSceneDesc d = good_desc(); d.vertex_count = 3; return create(d); }
static EmberStatus c_material_past(void) { EmberSceneDesc d = good_desc(); d.material_count = 0; d.materials = NULL; return create(d); }
static EmberStatus c_camera_size(void) { EmberSceneDesc d = good_desc(); d.camera.width = 0; return create(d); }
static EmberStatus c_camera_fov(void) { EmberSceneDesc d = good_desc(); d.camera.fov_degrees = 180; return create(d); }
static EmberStatus c_nan_position(void) {
    static float bad[12]; memcpy(bad, P, sizeof bad); bad[4] = 0.0f / 0.0f;
    EmberSceneDesc d = good_desc(); d.positions = bad; return create(d);
}
static EmberStatus c_material_kind(void) {
    static const EmberMaterial bad[] = {{.kind = 3, .color = {0.5f, 0.5f, 0.5f}}};
    EmberSceneDesc d = good_desc(); d.materials = bad; return create(d);
}
static EmberStatus c_huge_count(void) { EmberSceneDesc d = good_desc(); d.triangle_count = 0xffffffffu; return create(d); }
/* The complete description (EmberSceneDesc2): one triangle, one diffuse EmberBsdf. */
static EmberBsdf BSDF;
static EmberSceneDesc2 good_desc2(void) {
    ember_bsdf_init(EMBER_BSDF_KIND_DIFFUSE, &BSDF);
    EmberSceneDesc2 d = {.positions = P, .vertex_count = 4, .indices = IDX, .triangle_count = 1, .triangle_materials = MAT,
                         .materials = &BSDF, .material_count = 1, .camera = good_desc().camera};
    return d;
}
static EmberStatus create2(EmberSceneDesc2 d) { EmberScene s; return ember_scene_create2(&d, &s); }
static EmberStatus c2_bsdf_kind(void) { EmberSceneDesc2 d = good_desc2(); BSDF.kind = 8; return create2(d); }
static EmberStatus c2_texture_slot(void) { EmberSceneDesc2 d = good_desc2(); BSDF.textures[EMBER_TEXTURE_SLOT_DIFFUSE] = 0; return create2(d); }
static EmberStatus c2_pixels_null(void) {
    EmberSceneDesc2 d = good_desc2();
    static EmberTexture t;
    ember_texture_init(EMBER_TEXTURE_KIND_BITMAP, &t);
    t.width = t.height = 2;
    d.textures = &t, d.texture_count = 1;
    return create2(d);
}
static EmberStatus c2_light_kind(void) {
    EmberSceneDesc2 d = good_desc2();
    static EmberLight l;
    ember_light_init(EMBER_LIGHT_KIND_POINT, &l);
    l.kind = 9;
    d.lights = &l, d.light_count = 1;
    return create2(d);
}
static EmberStatus c2_filter_kind(void) { EmberSceneDesc2 d = good_desc2(); d.filter.kind = 3; return create2(d); }
static EmberStatus c2_normals_zero(void) { static const float N[12] = {0}; EmberSceneDesc2 d = good_desc2(); d.normals = N; return create2(d); }
static EmberStatus c2_init_kind(void) { EmberBsdf b; return ember_bsdf_init(99, &b); }
static EmberStatus c_builtin_unknown(void) { EmberScene s; return ember_scene_builtin("teapot", 8, 8, &s); }
static EmberStatus c_builtin_null(void) { EmberScene s; return ember_scene_builtin(NULL, 8, 8, &s); }
static EmberStatus c_dead_scene(void) { return ember_scene_destroy(dead_scene); }
static EmberStatus c_zero_handle(void) { return ember_render_passes(0, 1); }
static EmberStatus c_renderer_dead_scene(void) { EmberRenderSettings st = pt(); EmberRenderer r; return ember_renderer_create(dead_scene, &st, NULL, &r); }
static EmberStatus c_settings_null(void) { EmberRenderer r; return ember_renderer_create(scene, NULL, NULL, &r); }
static EmberStatus c_estimator_null(void) { EmberRenderSettings st = pt(); st.estimator = NULL; return settings_with(st); }
static EmberStatus c_estimator_unknown(void) { EmberRenderSettings st = pt(); st.estimator = "mlt"; return settings_with(st); }
static EmberStatus c_depth(void) { EmberRenderSettings st = pt(); st.max_depth = -5; return settings_with(st); }
static EmberStatus c_light_paths(void) { EmberRenderSettings st = pt(); st.estimator = "lvcbpt"; st.light_paths = 0xffffffffu; return settings_with(st); }
static EmberStatus c_radius(void) { EmberRenderSettings st = pt(); st.estimator = "vcm"; st.radius_footprints = -1.0f; return settings_with(st); }
static EmberStatus c_option_unknown(void) { EmberRenderSettings st = pt(); st.estimator = "spcbpt"; st.options = "subspaces=16 spp=4"; return settings_with(st); }
static EmberStatus c_option_value(void) { EmberRenderSettings st = pt(); st.estimator = "spcbpt"; st.options = "subspaces=many"; return settings_with(st); }
static EmberStatus c_option_form(void) { EmberRenderSettings st = pt(); st.options = "reuse"; return settings_with(st); }
static EmberStatus c_option_range(void) { EmberRenderSettings st = pt(); st.estimator = "bpf"; st.options = "beta=-1"; return settings_with(st); }
static EmberStatus c_callback_null(void) {
    EmberRenderSettings st = pt(); EmberRayCallbacks cb = {.user_data = NULL, .intersect = NULL, .occluded = never}; EmberRenderer r;
    return ember_renderer_create(scene, &st, &cb, &r);
}
static EmberStatus c_image_size(void) { float rgb[3]; return ember_renderer_image(renderer, rgb, 3); }
static EmberStatus c_image_null(void) { return ember_renderer_image(renderer, NULL, 8 * 8 * 3); }
static EmberStatus c_size_null(void) { uint32_t w; return ember_renderer_size(renderer, &w, NULL); }
static EmberStatus c_dead_renderer(void) { return ember_render_passes(dead_renderer, 1); }
static EmberStatus c_map_unopened(void) { return ember_phase_map(renderer, 0); }
static EmberStatus c_end_unopened(void) { return ember_phase_end(renderer); }
/* A fresh renderer's first phase (setup or pass 0), ended with no chunk mapped, then a
 * chunk mapped twice. */
static EmberRenderer phased;
static EmberStatus c_end_unmapped(void) {
    EmberPhaseInfo info;
    EmberStatus s = ember_pass_start(phased, 0);
    if (s == EMBER_STATUS_OK) s = ember_phase_begin(phased, &info);
    return s == EMBER_STATUS_OK ? ember_phase_end(phased) : s;
}
static EmberStatus c_map_twice(void) {
    EmberStatus s = ember_phase_map(phased, 0);
    return s == EMBER_STATUS_OK ? ember_phase_map(phased, 0) : s;
}
static EmberStatus c_begin_open(void) { EmberPhaseInfo info; return ember_phase_begin(phased, &info); }
/* 65536 x 65536: the film alone is 240 GiB (on a machine with more available, this row
 * would allocate it; the memory-limit rows below do not depend on the machine). */
static EmberStatus c_huge_camera(void) {
    EmberStatus s = ember_scene_builtin("cornell-box", 65536, 65536, &case_scene);
    EmberRenderSettings st = pt();
    return s == EMBER_STATUS_OK ? ember_renderer_create(case_scene, &st, NULL, &case_renderer) : s;
}
static EmberStatus c_memory_limit(void) { EmberRenderSettings st = pt(); st.options = "memory-limit=1K"; return ember_renderer_create(scene, &st, NULL, &case_renderer); }
static EmberStatus c_memory_light_paths(void) {
    EmberRenderSettings st = pt(); st.estimator = "lvcbpt"; st.light_paths = 4000000; st.options = "memory-limit=64M";
    return ember_renderer_create(scene, &st, NULL, &case_renderer);
}
static EmberStatus c_memory_limit_form(void) { EmberRenderSettings st = pt(); st.options = "memory-limit=lots"; return settings_with(st); }
static EmberStatus c_threads_max(void) {
    EmberRenderSettings st = pt(); st.threads = 0xffffffffu;
    EmberStatus s = ember_renderer_create(scene, &st, NULL, &case_renderer);
    return s == EMBER_STATUS_OK ? ember_render_passes(case_renderer, 1) : s;
}
static EmberStatus render_with_hit(FixedHit f) {
    static FixedHit hit; hit = f;
    EmberRenderSettings st = pt(); st.threads = 4;
    EmberRayCallbacks cb = {.user_data = &hit, .intersect = fixed_intersect, .occluded = never};
    EmberStatus s = ember_renderer_create(scene, &st, &cb, &case_renderer);
    return s == EMBER_STATUS_OK ? ember_render_passes(case_renderer, 1) : s;
}
static EmberStatus c_hit_primitive(void) { return render_with_hit((FixedHit){1.0f, 1000, 0.2f, 0.2f}); }
static EmberStatus c_hit_t(void) { return render_with_hit((FixedHit){NAN, 0, 0.2f, 0.2f}); }
static EmberStatus c_hit_outside(void) { return render_with_hit((FixedHit){1.0f, 0, 0.8f, 0.8f}); }
static EmberStatus c_hit_nan(void) { return render_with_hit((FixedHit){1.0f, 0, NAN, 0.2f}); }
/* The host's own threads: the chunk's map fails and the chunk stays unmapped. */
static EmberStatus c_hit_phase_map(void) {
    static FixedHit hit = {1.0f, 0, 0.8f, 0.8f};
    EmberRenderSettings st = pt();
    EmberRayCallbacks cb = {.user_data = &hit, .intersect = fixed_intersect, .occluded = never};
    EmberPhaseInfo info;
    EmberStatus s = ember_renderer_create(scene, &st, &cb, &case_renderer);
    if (s == EMBER_STATUS_OK) s = ember_pass_start(case_renderer, 0);
    if (s == EMBER_STATUS_OK) s = ember_phase_begin(case_renderer, &info);
    return s == EMBER_STATUS_OK ? ember_phase_map(case_renderer, 0) : s;
}
/* Rounding just outside the triangle is tolerated (1e-4). */
static EmberStatus c_hit_rounding(void) { return render_with_hit((FixedHit){1.0f, 1, -1e-6f, 1.0f + 1e-6f}); }

/* Films (issue 50): `film` is `exported`'s (pt, seed 1, max depth 4, 8x8, one pass). */
static EmberRenderer exported;
static uint8_t film[16384];
static size_t film_len;
static uint8_t damaged[sizeof film];
/* A renderer of `sc` with `st` (and `cb`), then the import of `len` bytes of `bytes`. */
static EmberStatus import_into(EmberScene sc, EmberRenderSettings st, const EmberRayCallbacks *cb, const uint8_t *bytes, size_t len) {
    EmberStatus s = ember_renderer_create(sc, &st, cb, &case_renderer);
    return s == EMBER_STATUS_OK ? ember_film_import(case_renderer, bytes, len) : s;
}
static EmberStatus c_export_written_null(void) { return ember_film_export(exported, film, sizeof film, NULL); }
/* Too small: refused, nothing written past the capacity (ASan), and *written says the size. */
static EmberStatus c_export_capacity(void) {
    static uint8_t small[16];
    size_t written = 0;
    EmberStatus s = ember_film_export(exported, small, sizeof small, &written);
    return written == film_len ? s : EMBER_STATUS_PANIC;
}
static EmberStatus c_import_null(void) { return import_into(scene, pt(), NULL, NULL, film_len); }
static EmberStatus c_import_checksum(void) {
    memcpy(damaged, film, film_len);
    damaged[film_len / 2] ^= 0x10;
    return import_into(scene, pt(), NULL, damaged, film_len);
}
static EmberStatus c_import_truncated(void) { return import_into(scene, pt(), NULL, film, film_len - 100); }
static EmberStatus c_import_magic(void) { return import_into(scene, pt(), NULL, (const uint8_t *)"a PNG, perhaps", 14); }
static EmberStatus c_import_estimator(void) { EmberRenderSettings st = pt(); st.estimator = "bdpt"; return import_into(scene, st, NULL, film, film_len); }
static EmberStatus c_import_seed(void) { EmberRenderSettings st = pt(); st.seed = 2; return import_into(scene, st, NULL, film, film_len); }
static EmberStatus c_import_depth(void) { EmberRenderSettings st = pt(); st.max_depth = -1; return import_into(scene, st, NULL, film, film_len); }
static EmberStatus c_import_size(void) {
    EmberSceneDesc d = good_desc(); d.camera.width = 16;
    EmberStatus s = ember_scene_create(&d, &case_scene);
    return s == EMBER_STATUS_OK ? import_into(case_scene, pt(), NULL, film, film_len) : s;
}
static EmberStatus c_import_scene(void) {
    static const float brighter[] = {0, 0, 0, 6, 6, 6};
    EmberSceneDesc d = good_desc(); d.triangle_emission = brighter;
    EmberStatus s = ember_scene_create(&d, &case_scene);
    return s == EMBER_STATUS_OK ? import_into(case_scene, pt(), NULL, film, film_len) : s;
}
static EmberStatus c_import_tracer(void) {
    static FixedHit hit = {1.0f, 0, 0.2f, 0.2f};
    EmberRayCallbacks cb = {.user_data = &hit, .intersect = fixed_intersect, .occluded = never};
    return import_into(scene, pt(), &cb, film, film_len);
}
static EmberStatus c_import_after_pass(void) { return ember_film_import(exported, film, film_len); }
static EmberStatus c_pass_start_after_import(void) {
    EmberStatus s = import_into(scene, pt(), NULL, film, film_len);
    return s == EMBER_STATUS_OK ? ember_pass_start(case_renderer, 1) : s;
}
static EmberStatus c_export_out_of_order(void) {
    EmberRenderSettings st = pt();
    size_t written;
    EmberStatus s = ember_renderer_create(scene, &st, NULL, &case_renderer);
    if (s == EMBER_STATUS_OK) s = ember_pass_start(case_renderer, 3);
    return s == EMBER_STATUS_OK ? ember_film_export(case_renderer, NULL, 0, &written) : s;
}

typedef struct { const char *name; EmberStatus (*call)(void); EmberStatus want; const char *message; } Case;

int main(void) {
    /* Unbuffered: a row that crashes the program leaves the rows before it on record. */
    setvbuf(stdout, NULL, _IONBF, 0);
    EmberSceneDesc d = good_desc();
    if (ember_scene_create(&d, &scene) != EMBER_STATUS_OK) { fprintf(stderr, "setup: %s\n", ember_last_error()); return 1; }
    if (ember_scene_create(&d, &dead_scene) != EMBER_STATUS_OK || ember_scene_destroy(dead_scene) != EMBER_STATUS_OK) return 1;
    EmberRenderSettings st = pt();
    if (ember_renderer_create(scene, &st, NULL, &renderer) != EMBER_STATUS_OK) { fprintf(stderr, "setup: %s\n", ember_last_error()); return 1; }
    if (ember_renderer_create(scene, &st, NULL, &dead_renderer) != EMBER_STATUS_OK || ember_renderer_destroy(dead_renderer) != EMBER_STATUS_OK) return 1;
    if (ember_renderer_create(scene, &st, NULL, &phased) != EMBER_STATUS_OK) return 1;
    if (ember_renderer_create(scene, &st, NULL, &exported) != EMBER_STATUS_OK || ember_render_passes(exported, 1) != EMBER_STATUS_OK ||
        ember_film_export(exported, NULL, 0, &film_len) != EMBER_STATUS_OK || film_len > sizeof film ||
        ember_film_export(exported, film, sizeof film, &film_len) != EMBER_STATUS_OK) {
        fprintf(stderr, "setup: the film (%zu bytes): %s\n", film_len, ember_last_error());
        return 1;
    }
    /* A new scene may reuse the destroyed one's slot: the old handle must stay dead. */
    EmberScene reuse;
    if (ember_scene_create(&d, &reuse) != EMBER_STATUS_OK) return 1;

    const Case cases[] = {
        {"desc null", c_desc_null, EMBER_STATUS_NULL_POINTER, "desc is null"},
        {"output null", c_out_null, EMBER_STATUS_NULL_POINTER, "scene is null"},
        {"positions null with a count", c_positions_null, EMBER_STATUS_NULL_POINTER, "positions"},
        {"vertex index past the positions", c_index_past, EMBER_STATUS_INVALID_ARGUMENT, "indexes a vertex past"},
        {"material index past the materials", c_material_past, EMBER_STATUS_INVALID_ARGUMENT, "material 0 is past"},
        {"camera width 0", c_camera_size, EMBER_STATUS_INVALID_ARGUMENT, "camera size"},
        {"camera fov 180", c_camera_fov, EMBER_STATUS_INVALID_ARGUMENT, "fov_degrees"},
        {"NaN position", c_nan_position, EMBER_STATUS_INVALID_ARGUMENT, "position 1 is not finite"},
        {"material kind 3", c_material_kind, EMBER_STATUS_INVALID_ARGUMENT, "materials[0].kind 3 is not an EmberMaterialKind (0..=2"},
        {"triangle count overflowing", c_huge_count, EMBER_STATUS_INVALID_ARGUMENT, "too large"},
        {"desc2: bsdf kind 8", c2_bsdf_kind, EMBER_STATUS_INVALID_ARGUMENT, "materials[0].kind 8 is not an EmberBsdfKind (0..=7"},
        {"desc2: texture past the textures", c2_texture_slot, EMBER_STATUS_INVALID_ARGUMENT, "materials[0].textures[0] (diffuse) 0 is neither -1 nor a texture index (0..0)"},
        {"desc2: bitmap without pixels", c2_pixels_null, EMBER_STATUS_NULL_POINTER, "textures[0].pixels (for 12 floats) is null"},
        {"desc2: light kind 9", c2_light_kind, EMBER_STATUS_INVALID_ARGUMENT, "lights[0].kind 9 is not an EmberLightKind"},
        {"desc2: filter kind 3", c2_filter_kind, EMBER_STATUS_INVALID_ARGUMENT, "filter.kind 3 is not an EmberFilterKind"},
        {"desc2: zero normals", c2_normals_zero, EMBER_STATUS_INVALID_ARGUMENT, "normals[0] is zero"},
        {"bsdf init: kind 99", c2_init_kind, EMBER_STATUS_INVALID_ARGUMENT, "kind 99 is not an EmberBsdfKind"},
        {"unknown built-in scene", c_builtin_unknown, EMBER_STATUS_INVALID_ARGUMENT, "teapot"},
        {"built-in name null", c_builtin_null, EMBER_STATUS_NULL_POINTER, "name is null"},
        {"destroyed scene destroyed again", c_dead_scene, EMBER_STATUS_INVALID_HANDLE, "not a live scene"},
        {"handle 0", c_zero_handle, EMBER_STATUS_INVALID_HANDLE, "not a live renderer"},
        {"renderer on a destroyed scene", c_renderer_dead_scene, EMBER_STATUS_INVALID_HANDLE, "not a live scene"},
        {"settings null", c_settings_null, EMBER_STATUS_NULL_POINTER, "settings is null"},
        {"estimator null", c_estimator_null, EMBER_STATUS_NULL_POINTER, "settings.estimator"},
        {"unknown estimator", c_estimator_unknown, EMBER_STATUS_INVALID_CONFIG, "no estimator 'mlt'"},
        {"max_depth -5", c_depth, EMBER_STATUS_INVALID_CONFIG, "max_depth -5"},
        {"light_paths out of range", c_light_paths, EMBER_STATUS_INVALID_CONFIG, "light-paths = 4294967295 is outside"},
        {"negative radius", c_radius, EMBER_STATUS_INVALID_CONFIG, "vcm"},
        {"option that is not an estimator's", c_option_unknown, EMBER_STATUS_INVALID_CONFIG, "no estimator option 'spp'"},
        {"option value not a number", c_option_value, EMBER_STATUS_INVALID_CONFIG, "'many'"},
        {"option without a value", c_option_form, EMBER_STATUS_INVALID_CONFIG, "not name=value"},
        {"option value out of range", c_option_range, EMBER_STATUS_INVALID_CONFIG, "beta"},
        {"camera 65536x65536", c_huge_camera, EMBER_STATUS_OUT_OF_MEMORY, "lower the camera's width and height"},
        {"memory-limit below the film", c_memory_limit, EMBER_STATUS_OUT_OF_MEMORY, "more than the 1.0 KiB of the memory-limit option"},
        {"light paths past memory-limit", c_memory_light_paths, EMBER_STATUS_OUT_OF_MEMORY, "lower settings.light_paths"},
        {"memory-limit not a size", c_memory_limit_form, EMBER_STATUS_INVALID_CONFIG, "memory-limit: 'lots' is not a size"},
        {"threads UINT32_MAX (capped)", c_threads_max, EMBER_STATUS_OK, ""},
        {"callback null", c_callback_null, EMBER_STATUS_NULL_POINTER, "callbacks.intersect"},
        {"image of the wrong size", c_image_size, EMBER_STATUS_INVALID_ARGUMENT, "holds 192 floats"},
        {"image null", c_image_null, EMBER_STATUS_NULL_POINTER, "rgb is null"},
        {"size output null", c_size_null, EMBER_STATUS_NULL_POINTER, "height is null"},
        {"destroyed renderer", c_dead_renderer, EMBER_STATUS_INVALID_HANDLE, "not a live renderer"},
        {"map with no phase open", c_map_unopened, EMBER_STATUS_INVALID_ARGUMENT, "no phase is open"},
        {"end with no phase open", c_end_unopened, EMBER_STATUS_INVALID_ARGUMENT, "no phase is open"},
        {"end with a chunk not mapped", c_end_unmapped, EMBER_STATUS_INVALID_ARGUMENT, "chunk 0 of 1 was not mapped"},
        {"a chunk mapped twice", c_map_twice, EMBER_STATUS_INVALID_ARGUMENT, "chunk 0 was already mapped"},
        {"begin while a phase is open", c_begin_open, EMBER_STATUS_INVALID_ARGUMENT, "already open"},
        {"callback names triangle 1000", c_hit_primitive, EMBER_STATUS_CALLBACK_ERROR, "returned primitive 1000 of 2 triangles"},
        {"callback returns t NaN", c_hit_t, EMBER_STATUS_CALLBACK_ERROR, "returned t = NaN outside (0, t_max"},
        {"callback barycentrics outside the triangle", c_hit_outside, EMBER_STATUS_CALLBACK_ERROR, "barycentrics (0.8, 0.8) outside the triangle"},
        {"callback barycentrics NaN", c_hit_nan, EMBER_STATUS_CALLBACK_ERROR, "barycentrics (NaN, 0.2)"},
        {"callback error mapping a chunk", c_hit_phase_map, EMBER_STATUS_CALLBACK_ERROR, "(0.8, 0.8) outside the triangle (b1, b2 >= 0 and b1 + b2 <= 1, to within 0.0001); chunk 0 was not mapped"},
        {"callback barycentrics rounded past an edge", c_hit_rounding, EMBER_STATUS_OK, ""},
        {"film export: written null", c_export_written_null, EMBER_STATUS_NULL_POINTER, "written is null"},
        {"film export: capacity too small", c_export_capacity, EMBER_STATUS_INVALID_ARGUMENT, "capacity 16 is below the"},
        {"film import: bytes null", c_import_null, EMBER_STATUS_NULL_POINTER, "bytes is null"},
        {"film import: a byte damaged", c_import_checksum, EMBER_STATUS_INVALID_FILM, "checksum: the bytes differ from those exported"},
        {"film import: truncated", c_import_truncated, EMBER_STATUS_INVALID_FILM, "size: a 8x8 film takes"},
        {"film import: not a film", c_import_magic, EMBER_STATUS_INVALID_FILM, "magic"},
        {"film import: another estimator's film", c_import_estimator, EMBER_STATUS_FILM_MISMATCH, "estimator: the film's is pt, this renderer's bdpt"},
        {"film import: another seed's film", c_import_seed, EMBER_STATUS_FILM_MISMATCH, "seed: the film's is 1, this renderer's 2"},
        {"film import: another max depth's film", c_import_depth, EMBER_STATUS_FILM_MISMATCH, "max depth: the film's is 4, this renderer's unbounded"},
        {"film import: a film of another size", c_import_size, EMBER_STATUS_FILM_MISMATCH, "size: the film's is 8x8, this renderer's 16x8"},
        {"film import: another scene's film", c_import_scene, EMBER_STATUS_FILM_MISMATCH, "scene: the film's is hash"},
        {"film import: the BVH's film, callbacks now", c_import_tracer, EMBER_STATUS_FILM_MISMATCH, "tracer: the film's is the built-in BVH, this renderer's the engine's callbacks"},
        {"film import after a pass", c_import_after_pass, EMBER_STATUS_INVALID_ARGUMENT, "holds 1 pass:"},
        {"pass start after a film import", c_pass_start_after_import, EMBER_STATUS_INVALID_ARGUMENT, "continues an imported film"},
        {"film export after a pass out of order", c_export_out_of_order, EMBER_STATUS_INVALID_ARGUMENT, "started pass 3 where one render's next pass was 0"},
    };
    int failed = 0;
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        EmberStatus got = cases[i].call();
        const char *msg = ember_last_error();
        bool ok = got == cases[i].want && strstr(msg, cases[i].message) != NULL;
        printf("%-50s %s (status %d: %s)\n", cases[i].name, ok ? "ok" : "FAILED", (int)got, msg);
        if (!ok) { failed++; printf("    wanted status %d with \"%s\"\n", (int)cases[i].want, cases[i].message); }
        if (case_renderer) { ember_renderer_destroy(case_renderer); case_renderer = 0; }
        if (case_scene) { ember_scene_destroy(case_scene); case_scene = 0; }
    }
    /* A success clears the message. */
    uint32_t w, h;
    if (ember_renderer_size(renderer, &w, &h) != EMBER_STATUS_OK || strcmp(ember_last_error(), "") != 0 || w != 8) { printf("success did not clear the message\n"); failed++; }
    /* The phase left open above still ends once its chunk is mapped. */
    if (ember_phase_end(phased) != EMBER_STATUS_OK) { printf("the open phase did not end: %s\n", ember_last_error()); failed++; }
    ember_renderer_destroy(phased);
    ember_renderer_destroy(exported);
    ember_renderer_destroy(renderer);
    ember_scene_destroy(scene);
    ember_scene_destroy(reuse);
    printf("%d of %zu error cases failed\n", failed, sizeof cases / sizeof cases[0]);
    return failed ? 1 : 0;
}
