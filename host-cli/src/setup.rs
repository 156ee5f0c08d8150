//! From a command's options to a ready renderer: the scene it names (a Mitsuba file or a
//! built-in scene), the estimator (`--estimator auto`'s race, [`crate::auto`]), the
//! scene plan ([`crate::plan`]), the memory check, and the setup phases run
//! ([`CoreRenderer`]).

use std::path::Path;
use std::time::Instant;

use ember_core::estimators::Renderer;
use ember_core::render::Film;
use ember_core::scene::builtin;
use ember_formats::mitsuba;
use ember_host::scene::PreparedScene;

use crate::cli::{DEFAULT_RESOLUTION, EstimatorChoice, RenderArgs};
use crate::estimators::{Built, CoreRenderer};

/// The built-in scene's resolution under these options (for the estimator wiring).
pub fn builtin_resolution(args: &RenderArgs) -> (u32, u32) {
    args.resolution_or(DEFAULT_RESOLUTION)
}

/// Build the built-in scene `--builtin` names (the Cornell box by default) at the requested resolution.
pub fn prepare_builtin(args: &RenderArgs) -> Result<PreparedScene, String> {
    let (w, h) = builtin_resolution(args);
    let (name, builder) = match args.builtin.as_deref() {
        Some(ember_core::scene::builtin_glass::GLASS_SPHERES) => ("built-in glass-spheres", ember_core::scene::builtin_glass::glass_spheres(w, h)),
        _ => ("built-in Cornell box", builtin::cornell_box(w, h)),
    };
    let (scene, geometry, warnings) = builder.build().map_err(|e| format!("built-in scene: {e}"))?;
    let mut prepared = PreparedScene::new(name.into(), scene, &geometry, warnings, None, None, Vec::new());
    choose_simd(&mut prepared, args.simd.as_deref())?;
    Ok(prepared)
}

/// Set the instruction sets: `option` (`--simd`) if given, else the environment's
/// `EMBER_SIMD`, else, for the ray queries, `Isa::best` (AVX2 where the machine has it)
/// and, for the lane kernels, the widest set (`ember_host::accel::isa`). Images do not
/// depend on them.
fn choose_simd(prepared: &mut PreparedScene, option: Option<&str>) -> Result<(), String> {
    let isa = ember_host::accel::Isa::select_with_env(option).map_err(|e| e.to_string())?;
    prepared.accel.set_isa(isa).map_err(|e| e.to_string())?;
    // The lane kernels: the same set if one was named, else the widest (module `isa`).
    let shading = ember_host::accel::Isa::select_shading_with_env(option).map_err(|e| e.to_string())?;
    prepared.accel.set_shading_level(shading);
    Ok(())
}

/// Load a Mitsuba 3 XML scene; `width`/`height` override the file's film.
pub fn prepare_file(path: &Path, width: Option<u32>, height: Option<u32>, defaults: Vec<(String, String)>) -> Result<PreparedScene, String> {
    prepare_file_with(path, width, height, defaults, None)
}

/// [`prepare_file`] with `--simd`'s value.
fn prepare_file_with(
    path: &Path,
    width: Option<u32>,
    height: Option<u32>,
    defaults: Vec<(String, String)>,
    simd: Option<&str>,
) -> Result<PreparedScene, String> {
    let loaded = mitsuba::load_scene(path, &mitsuba::LoadOptions { defaults, width, height }).map_err(|e| e.to_string())?;
    let mut prepared = PreparedScene::build(path.display().to_string(), loaded.builder, loaded.max_depth, loaded.spp, loaded.warnings)?;
    prepared.inputs = std::iter::once(path.to_path_buf()).chain(loaded.inputs).collect();
    choose_simd(&mut prepared, simd)?;
    Ok(prepared)
}

/// The scene a `render` command names (a file, or the built-in one).
pub fn prepare(args: &RenderArgs) -> Result<PreparedScene, String> {
    match &args.scene {
        Some(path) => prepare_file_with(path, args.width, args.height, args.defines.pairs.clone(), args.simd.as_deref()),
        None if !args.defines.pairs.is_empty() => Err("-D sets parameters of a scene file; the built-in scenes have none (give a SCENE)".into()),
        None => prepare_builtin(args),
    }
}

/// [`prepare_file`] at the file's resolution, for commands that load the scene once per
/// run (convergence, suite); the scene's warnings (an unused `-D` among them) are printed
/// on the first load only.
pub fn preparer<'a>(path: &'a Path, defaults: &'a [(String, String)]) -> impl Fn() -> Result<PreparedScene, String> + 'a {
    let warned = std::sync::Once::new();
    move || {
        let prepared = prepare_file(path, None, None, defaults.to_vec())?;
        warned.call_once(|| prepared.warnings.iter().for_each(|w| eprintln!("warning: {}: {w}", path.display())));
        Ok(prepared)
    }
}

/// The renderer a `render` command asks for, with what its report needs.
pub fn make_built(args: &RenderArgs) -> Result<Built, String> {
    make_built_at(args, Instant::now())
}

/// [`make_built`] for a program that started at `start` (`--estimator auto` counts its
/// pilot race in the `--time` budget that runs from there).
pub fn make_built_at(args: &RenderArgs, start: Instant) -> Result<Built, String> {
    let (r, film) = renderer_and_head(args, start)?;
    Ok(Built {
        scene: r.prepared.name.clone(),
        max_depth: r.renderer.params().max_depth.0,
        simd: r.prepared.accel.isa(),
        shading: r.prepared.accel.shading_level(),
        file_spp: r.prepared.spp,
        renderer: Box::new(r),
        film,
    })
}

pub use ember_host::setup::{check_memory, memory_budget};

/// The renderer a `render` command asks for, its setup run and reported on stderr.
pub fn make_core_renderer(args: &RenderArgs) -> Result<CoreRenderer, String> {
    make_core_renderer_at(args, Instant::now())
}

/// [`make_core_renderer`] for a program that started at `start`.
pub fn make_core_renderer_at(args: &RenderArgs, start: Instant) -> Result<CoreRenderer, String> {
    renderer_and_head(args, start).map(|(r, _)| r)
}

/// [`make_core_renderer_at`], with the passes `--estimator auto`'s race already rendered
/// at full size with the renderer's own configuration and seed, for the render to
/// continue ([`crate::auto::Head`]).
fn renderer_and_head(args: &RenderArgs, start: Instant) -> Result<(CoreRenderer, Option<Film>), String> {
    let mut prepared = prepare(args)?;
    let mut head = None;
    for w in &prepared.warnings {
        eprintln!("warning: {w}");
    }
    let max_depth = args.max_depth.or(prepared.max_depth).unwrap_or(-1);
    let kind = match args.estimator {
        EstimatorChoice::Fixed(kind) => kind,
        EstimatorChoice::Auto => {
            let load = |w: u32, h: u32| {
                let mut low = args.clone();
                (low.width, low.height) = (Some(w), Some(h));
                prepare(&low)
            };
            let (choice, back) = crate::auto::choose(args, prepared, max_depth, start, &load)?;
            prepared = back;
            for line in choice.describe() {
                eprintln!("{line}");
            }
            head = choice.head;
            choice.kind
        }
    };
    let asked = args.cache.config_for(kind);
    ember_host::setup::check_config(&asked)?;
    let config = if args.no_plan {
        asked
    } else {
        let plan = crate::plan::plan_for(&prepared, asked, max_depth, args.seed, args.thread_count(), ember_core::plan::pilot::DEFAULT_SAMPLES)?;
        for line in plan.describe() {
            eprintln!("plan       {line}");
        }
        plan.planned
    };
    check_memory(&prepared, &config, args.memory_limit)?;
    let r = CoreRenderer::with_model(prepared, config, max_depth, args.seed, args.thread_count(), args.model.as_deref())?;
    if let Renderer::Lvcbpt(l) = &r.renderer {
        eprintln!(
            "lvcbpt     M = {} light paths/pass, N = {}, counts: light tracing {:.4}, connection {:.4}",
            l.light_paths, l.config.connections, l.counts.light_tracing, l.counts.connection
        );
    }
    if let Some(model) = &args.model {
        eprintln!("{:<10} model loaded from {} (its preprocessing skipped)", r.kind().name(), model.display());
    }
    if let Renderer::Spcbpt(s) = &r.renderer {
        let rep = &s.report;
        if let Some(why) = rep.unbinned_because {
            eprintln!("spcbpt     light sources not binned ({why}): s = 1 is next-event estimation");
        }
        let phases = r.setup_times.iter().map(|(n, t)| format!("{n} {t:.2} s")).collect::<Vec<_>>().join(", ");
        eprintln!(
            "spcbpt     preprocessing {:.2} s ({phases}); {} eye × {} light subspaces ({} of them light-source bins{})",
            r.setup_seconds,
            rep.n_eye,
            rep.n_light,
            rep.light_source_bins,
            if rep.light_source_bins > 0 { ", s = 1 through the cache" } else { ", s = 1 by NEE" }
        );
        eprintln!("spcbpt     training: {} Adam steps in batches of {}; losses per epoch {:?}", rep.steps, rep.batch, rep.losses);
        eprintln!(
            "spcbpt     memory: D {:.1} MiB ({} paths, freed after training), trees {:.1} KiB, Γ {:.1} KiB",
            rep.dataset_bytes as f64 / 1048576.0,
            rep.dataset_paths,
            rep.tree_bytes as f64 / 1024.0,
            rep.gamma_bytes as f64 / 1024.0
        );
    }
    // The race's passes continue only where they are this render's own: the same
    // configuration after the plan (and the same seed, scene and depth by construction).
    let head = head.filter(|h| h.config == r.config).map(|h| h.film);
    Ok((r, head))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The notes `prepare_file` prints for a scene holding `emitters` (and one rectangle).
    fn notes(emitters: &str) -> Vec<String> {
        let xml = format!(
            r#"<scene version="3.0.0">
                <sensor type="perspective"><float name="fov" value="40"/>
                    <transform name="to_world"><lookat origin="0,0,5" target="0,0,0" up="0,1,0"/></transform>
                    <film type="hdrfilm"><integer name="width" value="4"/><integer name="height" value="4"/><rfilter type="box"/></film>
                </sensor>
                <shape type="rectangle"/>
                {emitters}
            </scene>"#
        );
        let loaded = mitsuba::load_scene_from_str(&xml, Path::new("notes.xml"), &mitsuba::LoadOptions::default()).unwrap();
        let (scene, geometry, warnings) = loaded.builder.build().unwrap();
        PreparedScene::new("notes.xml".into(), scene, &geometry, warnings, None, None, loaded.warnings).warnings
    }

    /// Dropped triangles are reported once, by the reader, with their cause (issue 51: a
    /// rectangle scaled by 1e38 was "zero area", and a second count followed the reader's
    /// line). Injected bug checked: the old count in `PreparedScene::new` makes each case two notes.
    #[test]
    fn dropped_triangles_are_reported_once_with_their_cause() {
        let lit = |shape: &str| notes(&format!(r#"<emitter type="constant"/>{shape}"#));
        let huge = lit(r#"<shape type="rectangle"><transform name="to_world"><scale value="1e38"/></transform></shape>"#);
        assert!(huge.len() == 1 && huge[0].contains("too large for single precision"), "{huge:?}");
        let flat = lit(r#"<shape type="rectangle"><transform name="to_world"><scale x="0" y="1" z="1"/></transform></shape>"#);
        assert!(flat.len() == 1 && flat[0].contains("2 of 2 triangles have zero area"), "{flat:?}");
    }

    /// Regression: every `constant` and `directional` emitter was reported as "emits
    /// nothing and was dropped" though it was kept and lit the scene. Injected bug checked:
    /// counting `light.power() <= 0` in `SceneBuilder::add_light` again fails here.
    #[test]
    fn lights_at_infinity_give_no_note() {
        for emitter in [r#"<emitter type="constant"/>"#, r#"<emitter type="directional"><vector name="direction" value="0,0,-1"/></emitter>"#] {
            assert_eq!(notes(emitter), Vec::<String>::new(), "{emitter}");
        }
    }

    /// Regression: a light whose power overflows f32 was left out of the light selection
    /// and the scene reported as having no light. Injected bug checked: removing the
    /// saturation in `Light::power` fails here.
    #[test]
    fn a_very_bright_light_is_a_light() {
        assert_eq!(
            notes(r#"<emitter type="point"><point name="position" value="0,0,1"/><rgb name="intensity" value="1e38"/></emitter>"#),
            Vec::<String>::new()
        );
    }

    /// Dark lights are counted as dropped, and a scene left with none is said to be unlit.
    #[test]
    fn dark_lights_are_reported_dropped_and_the_scene_unlit() {
        let n = notes(r#"<emitter type="point"><point name="position" value="0,0,1"/><rgb name="intensity" value="0"/></emitter>"#);
        assert!(n[0].starts_with("1 lights emit nothing and were dropped"), "{n:?}");
        assert!(n[1].contains("has no light"), "{n:?}");
        assert_eq!(n.len(), 2, "{n:?}");
        let none = notes("");
        assert_eq!(none.len(), 1, "{none:?}");
        assert!(none[0].contains("has no light"), "{none:?}");
    }
}
