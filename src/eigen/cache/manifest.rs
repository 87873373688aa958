//! An entry's manifest, `manifest.b3`: the blake3 hash of every file [`ModalCache::store`]
//! writes into the entry, `meta.json` included, sealed by the hash of the manifest itself.
//!
//! The text is a header line, one line `<blake3 hex>  <file name>` per file (the layout of
//! `b3sum`'s output) and a final line holding the blake3 hex of all the bytes before it:
//!
//! ```text
//! corrugation modal cache manifest 1
//! 3f2a…  frequencies_hz.npy
//! 9c41…  modes.npy
//! e07d…  meta.json
//! 51b8…
//! ```
//!
//! The manifest is written last, inside the entry's temporary directory before the rename
//! that publishes the entry, so an entry with a sealed manifest was written completely.
//!
//! [`ModalCache::store`]: super::ModalCache::store

use super::{FREQUENCIES_FILE, META_FILE, MODES_FILE};

/// First line of a manifest: what the file is and its format's version.
const HEADER: &str = "corrugation modal cache manifest 1\n";

/// The blake3 hashes (hex) of an entry's files, as its manifest lists them.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(super) struct Listed {
    /// Hash of `frequencies_hz.npy`.
    pub frequencies: String,
    /// Hash of `modes.npy`.
    pub modes: String,
    /// Hash of `meta.json`.
    pub meta: String,
}

/// Whether `s` is a blake3 hash as hex (64 lower-case hex digits), the form of the hashes and
/// of the entries' names.
pub(super) fn is_hex64(s: &str) -> bool {
    s.len() == 64 && s.bytes().all(|b| matches!(b, b'0'..=b'9' | b'a'..=b'f'))
}

/// The manifest text listing `l`.
pub(super) fn render(l: &Listed) -> String {
    let mut s = String::from(HEADER);
    for (hex, file) in [
        (&l.frequencies, FREQUENCIES_FILE),
        (&l.modes, MODES_FILE),
        (&l.meta, META_FILE),
    ] {
        s.push_str(&format!("{hex}  {file}\n"));
    }
    let seal = blake3::hash(s.as_bytes()).to_hex();
    s.push_str(&format!("{seal}\n"));
    s
}

/// The hashes a manifest lists, once its header, its seal (the final line's hash of the
/// bytes before it) and its lines are checked: each of the entry's three files exactly once.
/// The error is the reason the manifest is refused.
pub(super) fn parse(bytes: &[u8]) -> Result<Listed, &'static str> {
    let text = std::str::from_utf8(bytes).map_err(|_| "not UTF-8 text")?;
    let body_and_seal = text
        .strip_suffix('\n')
        .ok_or("truncated (no final line break)")?;
    let cut = body_and_seal
        .rfind('\n')
        .ok_or("truncated (no seal line)")?
        + 1;
    let (body, seal) = body_and_seal.split_at(cut);
    if !is_hex64(seal) {
        return Err("its last line is not a blake3 hash");
    }
    if blake3::hash(body.as_bytes()).to_hex().as_str() != seal {
        return Err("its own hash does not match its content (edited or corrupted)");
    }
    let lines = body.strip_prefix(HEADER).ok_or("unknown header line")?;
    let (mut frequencies, mut modes, mut meta) = (None, None, None);
    for line in lines.lines() {
        let (hex, file) = line
            .split_once("  ")
            .ok_or("a line is not `<hash>  <file>`")?;
        if !is_hex64(hex) {
            return Err("a line is not `<hash>  <file>`");
        }
        let slot = match file {
            FREQUENCIES_FILE => &mut frequencies,
            MODES_FILE => &mut modes,
            META_FILE => &mut meta,
            _ => return Err("it lists a file an entry does not hold"),
        };
        if slot.replace(hex.to_string()).is_some() {
            return Err("it lists a file twice");
        }
    }
    match (frequencies, modes, meta) {
        (Some(frequencies), Some(modes), Some(meta)) => Ok(Listed {
            frequencies,
            modes,
            meta,
        }),
        _ => Err("it does not list frequencies_hz.npy, modes.npy and meta.json"),
    }
}

#[cfg(test)]
mod tests {
    use super::{parse, render, Listed, HEADER};
    fn sample() -> Listed {
        Listed {
            frequencies: "a".repeat(64),
            modes: "b".repeat(64),
            meta: "c".repeat(64),
        }
    }

    #[test]
    fn a_rendered_manifest_parses_back() {
        let text = render(&sample());
        assert_eq!(parse(text.as_bytes()), Ok(sample()));
        assert_eq!(text.lines().count(), 5);
        assert!(text.contains(&format!("{}  meta.json\n", "c".repeat(64))));
    }

    /// Any change of a listed hash, a truncation, an extra or a missing line is refused.
    #[test]
    fn an_edited_or_truncated_manifest_is_refused() {
        let text = render(&sample());
        let edited = text.replacen("cccc", "cccd", 1);
        let resealed_short = {
            let body = format!("{HEADER}{}  modes.npy\n", "b".repeat(64));
            format!("{body}{}\n", blake3::hash(body.as_bytes()).to_hex())
        };
        let resealed_twice = {
            let body = format!("{HEADER}{0}  modes.npy\n{0}  modes.npy\n", "b".repeat(64));
            format!("{body}{}\n", blake3::hash(body.as_bytes()).to_hex())
        };
        for bad in [
            edited.as_str(),
            &text[..text.len() - 1],
            &text[..text.len() - 20],
            "",
            resealed_short.as_str(),
            resealed_twice.as_str(),
        ] {
            assert!(parse(bad.as_bytes()).is_err(), "{bad:?} accepted");
        }
    }
}
