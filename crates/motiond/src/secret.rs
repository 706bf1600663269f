//! The server's key: 32 random bytes in `<state_dir>/motiond.key` that only the server's
//! user may read, made at the first start that needs it, with which the server
//! authenticates what it writes for itself to read back (the references file's records,
//! crate::references) — HMAC-SHA256 (RFC 2104 over FIPS 180-4), so that a record edited
//! or planted by anyone who cannot read the key is refused.
//!
//! The key file is made whole under a temporary name (`O_CREAT | O_EXCL | O_NOFOLLOW`, mode
//! 0600) and linked to its name (never replacing one), and is read only when it is a
//! regular file of the server's user that its group and others may neither read nor write
//! ([`motion_config::private_dir`]). A process of the server's own user can read it: that user is
//! trusted as it is for the server's shared memory (docs/SECURITY.md).

use core::fmt::Write as _;

use hmac::{Hmac, Mac as _};
use sha2::Sha256;

use motion_config::private_dir::{Privacy, PrivateDir, PrivateDirError};

/// The key file's name in the state directory.
pub const KEY_FILE: &str = "motiond.key";

/// The key's length (HMAC-SHA256's block allows up to 64; 32 is SHA-256's output).
const KEY_BYTES: usize = 32;

/// A MAC's length in bytes.
pub const MAC_BYTES: usize = 32;

/// The server's key, as the MAC it starts every tag from.
#[derive(Clone)]
pub struct ServerKey(Hmac<Sha256>);

impl core::fmt::Debug for ServerKey {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("ServerKey(..)")
    }
}

impl ServerKey {
    /// The key in `dir`, made there first when there is none; refused when the file is not
    /// the server's own secret or not a key.
    pub fn load_or_create(dir: &PrivateDir) -> Result<Self, PrivateDirError> {
        let path = dir.file_path(KEY_FILE);
        let io = |what: &'static str, detail: String| PrivateDirError::Io {
            key: "[server] state_dir",
            path: path.clone(),
            what,
            detail,
        };
        // Twice at most: made by another start between our look and our link.
        for _ in 0..2 {
            if let Some(bytes) = dir.read_own(KEY_FILE, Privacy::Secret, KEY_BYTES as u64)? {
                let key: [u8; KEY_BYTES] =
                    bytes
                        .try_into()
                        .map_err(|bytes: Vec<u8>| PrivateDirError::Untrusted {
                            key: "[server] state_dir",
                            path: path.clone(),
                            why: format!(
                                "it holds {} bytes, not a key of {KEY_BYTES}",
                                bytes.len()
                            ),
                            fix: format!(
                                "remove it (`rm {}`): the server makes a new one (what it \
                                 authenticated with the old one is refused)",
                                path.display()
                            ),
                        })?;
                return Self::from_bytes(&key).ok_or_else(|| io("use", "not a key".into()));
            }
            let mut key = [0u8; KEY_BYTES];
            getrandom::fill(&mut key).map_err(|e| io("make a key", e.to_string()))?;
            let made = dir
                .create_whole(KEY_FILE, &key, 0o600)
                .map_err(|e| io("write", e.to_string()))?;
            if made {
                tracing::info!(
                    "made the server's key {} (it authenticates the references file)",
                    path.display()
                );
                return Self::from_bytes(&key).ok_or_else(|| io("use", "not a key".into()));
            }
        }
        Err(io("read or make", "it keeps changing".into()))
    }

    /// A key from its bytes (`None` only for a length HMAC refuses: none).
    pub fn from_bytes(bytes: &[u8]) -> Option<Self> {
        <Hmac<Sha256>>::new_from_slice(bytes).ok().map(Self)
    }

    fn mac(&self, parts: &[&[u8]]) -> Hmac<Sha256> {
        let mut mac = self.0.clone();
        for part in parts {
            // Each part with its length first: ("ab", "c") and ("a", "bc") differ.
            mac.update(&(part.len() as u64).to_le_bytes());
            mac.update(part);
        }
        mac
    }

    /// The MAC of `parts` (a domain string first, then the fields), as 64 hex digits.
    pub fn sign(&self, parts: &[&[u8]]) -> String {
        let tag = self.mac(parts).finalize().into_bytes();
        let mut text = String::with_capacity(2 * MAC_BYTES);
        for byte in tag {
            let _ = write!(text, "{byte:02x}");
        }
        text
    }

    /// Whether `tag` (hex, as [`sign`](Self::sign) makes it) is the MAC of `parts`; the
    /// comparison takes the same time whatever the tag.
    pub fn verify(&self, parts: &[&[u8]], tag: &str) -> bool {
        let Some(bytes) = from_hex(tag) else {
            return false;
        };
        self.mac(parts).verify_slice(&bytes).is_ok()
    }
}

fn from_hex(text: &str) -> Option<Vec<u8>> {
    if text.len() != 2 * MAC_BYTES {
        return None;
    }
    (0..text.len())
        .step_by(2)
        .map(|at| u8::from_str_radix(text.get(at..at + 2)?, 16).ok())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// RFC 4231 test case 2 ("Jefe", "what do ya want for nothing?") is HMAC-SHA256 of one
    /// message; `sign` frames its parts, so the vector is checked on the MAC underneath.
    #[test]
    fn hmac_sha256_matches_rfc_4231_test_case_2() {
        let mut mac = <Hmac<Sha256>>::new_from_slice(b"Jefe").expect("any length");
        mac.update(b"what do ya want for nothing?");
        let tag = mac.finalize().into_bytes();
        let hex: String = tag.iter().map(|b| format!("{b:02x}")).collect();
        assert_eq!(
            hex,
            "5bdcc146bf60754e6a042426089575c75a003f089d2739839dec58b964ec3843"
        );
    }

    /// The key is made once, 0600, and read back the same; a key file others may read, or
    /// of another length, is refused.
    #[test]
    fn the_key_is_made_once_private_and_refused_when_others_may_read_it() {
        use std::os::unix::fs::{MetadataExt as _, PermissionsExt as _};
        let path = std::env::temp_dir().join(format!("motiond-key-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&path);
        let dir = PrivateDir::open(&path, "[server] state_dir", 0o700).expect("made");
        let first = ServerKey::load_or_create(&dir).expect("made");
        let file = path.join(KEY_FILE);
        let meta = std::fs::metadata(&file).expect("the key file");
        assert_eq!((meta.mode() & 0o7777, meta.len()), (0o600, 32));
        let again = ServerKey::load_or_create(&dir).expect("read");
        let tag = first.sign(&[b"x"]);
        assert!(again.verify(&[b"x"], &tag), "the same key");
        std::fs::set_permissions(&file, std::fs::Permissions::from_mode(0o640)).expect("chmod");
        let error = ServerKey::load_or_create(&dir).expect_err("others may read it");
        assert!(error.to_string().contains("may read or write"), "{error}");
        std::fs::write(&file, b"short").expect("written");
        std::fs::set_permissions(&file, std::fs::Permissions::from_mode(0o600)).expect("chmod");
        let error = ServerKey::load_or_create(&dir).expect_err("not a key");
        assert!(error.to_string().contains("5 bytes"), "{error}");
        let _ = std::fs::remove_dir_all(&path);
    }

    #[test]
    fn a_tag_verifies_only_for_its_parts_and_its_key() {
        let key = ServerKey::from_bytes(&[7; KEY_BYTES]).expect("a key");
        let tag = key.sign(&[b"domain", b"ab", b"c"]);
        assert_eq!(tag.len(), 64);
        assert!(key.verify(&[b"domain", b"ab", b"c"], &tag));
        assert!(!key.verify(&[b"domain", b"a", b"bc"], &tag), "framed");
        assert!(!key.verify(&[b"domain", b"ab", b"d"], &tag));
        let other = ServerKey::from_bytes(&[8; KEY_BYTES]).expect("a key");
        assert!(!other.verify(&[b"domain", b"ab", b"c"], &tag));
        for bad in ["", "zz", &tag[..62], &format!("{tag}00")] {
            assert!(!key.verify(&[b"domain", b"ab", b"c"], bad), "{bad:?}");
        }
    }
}
