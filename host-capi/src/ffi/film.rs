//! Export and continue a render's film (`ember_film_export`, `ember_film_import`; the
//! byte format is `crate::film_state`).

use super::*;

/// The film's state as bytes, to continue the render later with `ember_film_import` (in
/// this process or another): the passes, their exact sums, and what they depend on
/// (estimator, configuration, seed, max depth, tracer, scene, size, film kind, ember build;
/// docs/embedding.md). With `bytes` null, `*written` gets the size needed and nothing is
/// written; else `capacity` must be at least that size (if not: `*written` gets it and
/// the call fails) and `*written` gets the bytes written.
///
/// # Safety
/// A non-null `bytes` must point to `capacity` writable bytes, a non-null `written` to a
/// writable `size_t` (null is refused).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ember_film_export(renderer: EmberRenderer, bytes: *mut u8, capacity: usize, written: *mut usize) -> EmberStatus {
    guard(|| {
        let shared = renderer_of(renderer)?;
        let st = crate::read(&shared.state)?;
        let written = unsafe { out(written, "written") }?;
        if let Some((pass, next)) = st.out_of_order {
            return Err(Error::arg(format!(
                "ember_pass_start started pass {pass} where one render's next pass was {next}: the film holds no passes 0..N to export"
            )));
        }
        let identity = st.film_identity();
        let need = crate::film_state::encoded_len(&identity)
            .ok_or_else(|| Error::arg("the film's bytes would not fit a size_t (or its configuration's text is past 65535 bytes)"))?;
        *written = need;
        if bytes.is_null() {
            return Ok(EmberStatus::Ok);
        }
        if capacity < need {
            return Err(Error::arg(format!("capacity {capacity} is below the {need} bytes the film needs (*written has the size)")));
        }
        // SAFETY: `capacity` (at least `need`) writable bytes at a non-null `bytes`, by the
        // caller's contract.
        let dst = unsafe { std::slice::from_raw_parts_mut(bytes, need) };
        let whole = st.whole()?;
        crate::film_state::encode(&identity, &whole, dst);
        Ok(EmberStatus::Ok)
    })
}

/// Continue the film `ember_film_export` wrote: `len` bytes at `bytes`. Only on a
/// renderer that has rendered (or started) no pass yet, of the same render: the same
/// estimator, configuration, seed, max depth, tracer (BVH or callbacks), scene, size and
/// ember build. Checked first: the magic, format version, size and checksum
/// (`EMBER_STATUS_INVALID_FILM`), then each of those fields (`EMBER_STATUS_FILM_MISMATCH`);
/// the message names the field. Afterwards `ember_renderer_passes` counts the imported
/// passes, the image is the mean over all, and `ember_render_passes` renders the next
/// passes as one render would have (bit for bit). The phase calls are refused.
///
/// # Safety
/// A non-null `bytes` must point to `len` readable bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ember_film_import(renderer: EmberRenderer, bytes: *const u8, len: usize) -> EmberStatus {
    guard(|| {
        let shared = renderer_of(renderer)?;
        if bytes.is_null() {
            return Err(null("bytes"));
        }
        if shared.phase_read()?.is_some() {
            return Err(Error::arg("a phase is open: a film is imported only before the first pass"));
        }
        let mut st = crate::write(&shared.state)?;
        if st.passes() > 0 || st.pass_started {
            let n = st.passes();
            return Err(Error::arg(format!(
                "the renderer holds {n} pass{}{}: a film is imported only before the first pass",
                if n == 1 { "" } else { "es" },
                if st.pass_started { " and has started one (ember_pass_start)" } else { "" }
            )));
        }
        // SAFETY: `len` readable bytes at a non-null `bytes`, by the caller's contract.
        let bytes = unsafe { std::slice::from_raw_parts(bytes, len) };
        let film = crate::film_state::decode(bytes, &st.film_identity())?;
        st.imported = (film.passes() > 0).then_some(film);
        Ok(EmberStatus::Ok)
    })
}
