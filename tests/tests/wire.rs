//! The render protocol across address spaces (`ember_core::render::wire`): every chunk's
//! output sent through bytes, as the browser's workers send it, gives the serial
//! runner's image bit for bit, and an instance that only receives state parts (never
//! film parts, never mapping) stays in step with the one that maps.

use ember_core::estimators::{ChunkOutput, PhaseBuffers};
use ember_core::estimators::{EstimatorKind, Renderer};
use ember_core::render::wire::Part;
use ember_core::render::{Context, Film, Phased, run_phases};
use ember_core::scene::builtin;
use ember_core::transport::RenderParams;
use ember_tests::tracer::BruteForce;

/// Every estimator on the Cornell box, two passes.
/// Injected bugs it caught: the second instance reducing the phase's outputs without
/// their state part (LVCBPT's, SPCBPT's and VCM's caches empty there: the instances leave
/// step, or the film differs once the first instance reads its cache from them); encoding
/// the film part without the splats (LT, BDPT images differ).
#[test]
fn bytes_between_instances_give_the_serial_image() {
    const SIZE: u32 = 20;
    let (scene, geometry, _) = builtin::cornell_box(SIZE, SIZE).build().expect("builds");
    let tracer = BruteForce::new(geometry);
    let ctx = Context { scene: &scene, tracer: &tracer };
    for kind in EstimatorKind::ALL {
        let params = RenderParams { seed: 3, ..Default::default() };
        let config = kind.default_config();
        let new = || Renderer::new(&scene, params, config).expect("config");
        let mut serial = new();
        let mut film_serial = Film::new(SIZE, SIZE);
        let mut buffers = PhaseBuffers::new();
        for pass in 0..2 {
            Phased::<BruteForce>::start_pass(&mut serial, pass);
            run_phases(&mut serial, &ctx, &mut film_serial, &mut buffers);
        }

        // a: maps and holds the film; b: receives state parts only.
        let (mut a, mut b) = (new(), new());
        let (mut film_a, mut film_b) = (Film::new(SIZE, SIZE), Film::new(0, 0));
        let (mut out_a, mut out_b) = (PhaseBuffers::new(), PhaseBuffers::new());
        let mut worker = ChunkOutput::default();
        let mut bytes = Vec::new();
        let mut sent = 0usize;
        for pass in 0..2 {
            Phased::<BruteForce>::start_pass(&mut a, pass);
            Phased::<BruteForce>::start_pass(&mut b, pass);
            while let Some(phase) = Phased::<BruteForce>::next_phase(&a) {
                assert_eq!(Phased::<BruteForce>::next_phase(&b), Some(phase), "{kind}: the instances left step");
                let mapped = out_a.for_phase(&phase);
                let received = out_b.for_phase(&phase);
                for (c, (m, r)) in mapped.iter_mut().zip(received.iter_mut()).enumerate() {
                    worker.reset(phase.chunk_range(c));
                    // A third instance would map here; `b` never maps, `a`'s map reads only
                    // the state every instance shares.
                    a.map(&ctx, &phase, &mut worker);
                    for (part, to_b) in [(Part::Film, false), (Part::State, false), (Part::State, true)] {
                        bytes.clear();
                        worker.encode(&phase, part, &mut bytes);
                        sent += bytes.len();
                        let dst = if to_b { &mut *r } else { &mut *m };
                        dst.decode(&phase, c, part, &bytes, &scene).expect("own bytes decode");
                    }
                }
                a.reduce(&ctx, &phase, mapped, &mut film_a);
                b.reduce(&ctx, &phase, received, &mut film_b);
            }
            assert_eq!(Phased::<BruteForce>::next_phase(&b), None, "{kind}: b has phases left");
        }
        assert!(sent > 0);
        assert_eq!(film_a.exact_sums(), film_serial.exact_sums(), "{kind}: the image through bytes differs from the serial one");
        // b's state must be a's: map one chunk of a next pass from each and compare bytes.
        Phased::<BruteForce>::start_pass(&mut a, 2);
        Phased::<BruteForce>::start_pass(&mut b, 2);
        let mut film_a2 = Film::new(SIZE, SIZE);
        let mut film_b2 = Film::new(SIZE, SIZE);
        let (mut o1, mut o2) = (PhaseBuffers::new(), PhaseBuffers::new());
        run_phases(&mut a, &ctx, &mut film_a2, &mut o1);
        run_phases(&mut b, &ctx, &mut film_b2, &mut o2);
        assert_eq!(film_a2.exact_sums(), film_b2.exact_sums(), "{kind}: the receiving instance's state differs");
    }
}
