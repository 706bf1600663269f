//! A remote's session on the wire: the opening, the grant, the secret both sides agree on
//! (X25519, never sent) and the attachment of every command (a MAC made with the secret, a
//! counter, the send time). Re-exported by [`crate::keys`].

use core::fmt;

use super::SessionId;

/// The secret of a session: 16 bytes both sides derive from the opening's X25519 keys
/// ([`KeyPair::agree`]), never sent; every command of the session carries a MAC made with it
/// ([`RequestMeta`]). All zero: no session.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct SessionToken(pub [u8; 16]);

impl SessionToken {
    /// No session.
    pub const NONE: Self = Self([0; 16]);

    /// Whether this is [`SessionToken::NONE`].
    pub fn is_none(self) -> bool {
        self == Self::NONE
    }
}

impl fmt::Debug for SessionToken {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // A secret: never in a log.
        f.write_str(if self.is_none() {
            "SessionToken(none)"
        } else {
            "SessionToken(…)"
        })
    }
}

/// Version byte of [`SessionOpen`], [`SessionGrant`] and [`RequestMeta`] (3: requests carry
/// a MAC instead of the session's secret).
pub const CONTRACT_VERSION: u8 = 3;

/// The payload of a session-opening query on `motiond/<name>/session/<identity>`: version
/// (u8, 3), the client's CLOCK_MONOTONIC when it sent the query (u64 LE, ns), the client's
/// X25519 public key for this opening (32 bytes) and the client's zenoh id as zenoh prints
/// it (ASCII hex, zero-padded to 32 bytes). 73 bytes. The bridge judges the session's later
/// time stamps against its own clock from here on, and ends the session when the transport
/// of that zenoh id closes (when the client is connected to it directly).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SessionOpen {
    /// The client's monotonic clock at sending, ns.
    pub sent_ns: u64,
    /// The client's X25519 public key ([`KeyPair`]).
    pub public: [u8; 32],
    /// The client's zenoh id as zenoh prints it, zero-padded ([`SessionOpen::zid`]).
    pub zid: [u8; 32],
}

impl SessionOpen {
    /// Bytes on the wire.
    pub const SIZE: usize = 73;

    /// An opening sent at `sent_ns` with the key `public` by the zenoh session `zid` (as
    /// zenoh prints it; more than 32 bytes are cut).
    pub fn new(sent_ns: u64, public: [u8; 32], zid: &str) -> Self {
        let mut padded = [0; 32];
        let len = zid.len().min(32);
        padded[..len].copy_from_slice(&zid.as_bytes()[..len]);
        Self {
            sent_ns,
            public,
            zid: padded,
        }
    }

    /// The client's zenoh id; `None` when the field holds none (or no ASCII).
    pub fn zid(&self) -> Option<&str> {
        let len = self.zid.iter().position(|&b| b == 0).unwrap_or(32);
        let zid = core::str::from_utf8(&self.zid[..len]).ok()?;
        (!zid.is_empty() && zid.is_ascii()).then_some(zid)
    }

    /// The 73 bytes.
    pub fn encode(self) -> [u8; 73] {
        let mut out = [0; 73];
        out[0] = CONTRACT_VERSION;
        out[1..9].copy_from_slice(&self.sent_ns.to_le_bytes());
        out[9..41].copy_from_slice(&self.public);
        out[41..73].copy_from_slice(&self.zid);
        out
    }

    /// From the payload; `None` for another size or version.
    pub fn decode(bytes: &[u8]) -> Option<Self> {
        let bytes = <&[u8; 73]>::try_from(bytes).ok()?;
        if bytes[0] != CONTRACT_VERSION {
            return None;
        }
        Some(Self {
            sent_ns: u64::from_le_bytes(bytes[1..9].try_into().ok()?),
            public: bytes[9..41].try_into().ok()?,
            zid: bytes[41..73].try_into().ok()?,
        })
    }
}

/// The bridge's answer to [`SessionOpen`]: version (u8, 3), the public [`SessionId`] (u128
/// LE, never zero) and the bridge's X25519 public key for this opening (32 bytes). 49
/// bytes. The session's secret is agreed from the two keys ([`KeyPair::agree`]); it never
/// travels, not even here.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SessionGrant {
    /// The session's public id (the client's liveliness token names it).
    pub session: SessionId,
    /// The bridge's X25519 public key.
    pub public: [u8; 32],
}

impl SessionGrant {
    /// Bytes on the wire.
    pub const SIZE: usize = 49;

    /// The 49 bytes.
    pub fn encode(self) -> [u8; 49] {
        let mut out = [0; 49];
        out[0] = CONTRACT_VERSION;
        out[1..17].copy_from_slice(&self.session.0.to_le_bytes());
        out[17..49].copy_from_slice(&self.public);
        out
    }

    /// From the reply's payload; `None` for another size or version, or a zero id.
    pub fn decode(bytes: &[u8]) -> Option<Self> {
        let bytes = <&[u8; 49]>::try_from(bytes).ok()?;
        if bytes[0] != CONTRACT_VERSION {
            return None;
        }
        let grant = Self {
            session: SessionId(u128::from_le_bytes(bytes[1..17].try_into().ok()?)),
            public: bytes[17..49].try_into().ok()?,
        };
        (grant.session.0 != 0).then_some(grant)
    }
}

/// One side's X25519 key pair for one session opening, made from 32 random bytes the caller
/// draws (this crate does no I/O). The session's secret ([`SessionToken`]) is agreed from
/// both sides' keys: anyone who sees the opening (a log, a peer on the path) sees the public
/// keys only. An active peer that answers the opening in the bridge's place is not kept out
/// by this (zenoh authentication and access control are: `crates/motion-bridge/README.md`, "Who is
/// who").
pub struct KeyPair {
    secret: x25519_dalek::StaticSecret,
    public: [u8; 32],
}

impl fmt::Debug for KeyPair {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("KeyPair")
            .field("public", &self.public)
            .finish_non_exhaustive()
    }
}

/// The domain of the session's secret (so it is never the hash of anything else).
const SESSION_DOMAIN: &[u8] = b"motiond-session-v3";

impl KeyPair {
    /// The key pair of the 32 random bytes `random`.
    pub fn from_random(random: [u8; 32]) -> Self {
        let secret = x25519_dalek::StaticSecret::from(random);
        let public = x25519_dalek::PublicKey::from(&secret).to_bytes();
        Self { secret, public }
    }

    /// This side's public key.
    pub fn public(&self) -> [u8; 32] {
        self.public
    }

    /// The secret of session `session` opened with the client's key `client` and the
    /// bridge's key `bridge` (one of them this pair's): the first 16 bytes of SHA3-256 over
    /// `"motiond-session-v3"`, the X25519 shared secret, `client`, `bridge` and the session
    /// id (u128 LE). `None` when the other key is no usable public key (the shared secret
    /// is all zero) or the result is zero.
    pub fn agree(
        &self,
        client: [u8; 32],
        bridge: [u8; 32],
        session: SessionId,
    ) -> Option<SessionToken> {
        use sha3::Digest as _;
        let theirs = if client == self.public {
            bridge
        } else {
            client
        };
        let shared = self
            .secret
            .diffie_hellman(&x25519_dalek::PublicKey::from(theirs));
        if !shared.was_contributory() {
            return None;
        }
        let digest = sha3::Sha3_256::new()
            .chain_update(SESSION_DOMAIN)
            .chain_update(shared.as_bytes())
            .chain_update(client)
            .chain_update(bridge)
            .chain_update(session.0.to_le_bytes())
            .finalize();
        let mut token = [0; 16];
        token.copy_from_slice(&digest[..16]);
        let token = SessionToken(token);
        (!token.is_none()).then_some(token)
    }
}

/// The attachment of a command query, 49 bytes: version (u8, 3), the public [`SessionId`]
/// (u128 LE; zero without a session: stop and e-stop only), a counter (u64 LE, rising with
/// every request of the session), the client's CLOCK_MONOTONIC when it sent the request (u64
/// LE, ns), and a MAC (16 bytes): the first 16 bytes of HMAC-SHA3-256 keyed by the
/// session's [`SessionToken`] over `"motiond-request-v3"`, the identity the request is sent
/// under (its UTF-8 bytes, then a zero byte), the request's payload as sent (the
/// `CommandRequest`'s 64 bytes) and bytes 1 to 32 of this attachment (id, counter, time).
///
/// The secret never travels with a command: a peer that sees one cannot make another. The
/// bridge refuses a counter it has seen (or one more than 1024 below the highest it has
/// seen) — a command replayed is not applied twice — and judges the send time against the
/// session's own clock as it learnt it when the session opened: a request that arrives more
/// than the bridge's `max_delay` later than the session's fastest (a renewal held up in a
/// network buffer must not restart a jog after the network came back), or that says it was
/// sent that much (at least 2 s) later than it could have been, is refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RequestMeta {
    /// The session ([`SessionId`] zero: none).
    pub session: SessionId,
    /// The session's request counter.
    pub counter: u64,
    /// The client's monotonic clock at sending, ns.
    pub sent_ns: u64,
    /// The MAC ([`RequestMeta::sign`]).
    pub mac: [u8; 16],
}

/// The domain of the request MAC (so it is never the MAC of anything else).
const MAC_DOMAIN: &[u8] = b"motiond-request-v3";

impl RequestMeta {
    /// Bytes on the wire.
    pub const SIZE: usize = 49;

    /// The attachment of a request without a session (stop and e-stop).
    pub const fn sessionless(sent_ns: u64) -> Self {
        Self {
            session: SessionId(0),
            counter: 0,
            sent_ns,
            mac: [0; 16],
        }
    }

    /// The attachment of `request` (its payload's bytes as sent) under `identity`, signed
    /// with `token`.
    pub fn sign(
        token: SessionToken,
        identity: &str,
        request: &[u8],
        session: SessionId,
        counter: u64,
        sent_ns: u64,
    ) -> Self {
        let mut meta = Self {
            session,
            counter,
            sent_ns,
            mac: [0; 16],
        };
        meta.mac = meta.mac_with(token, identity, request);
        meta
    }

    /// Whether the MAC is that of `request` under `identity` with `token` (compared in
    /// constant time).
    pub fn verify(&self, token: SessionToken, identity: &str, request: &[u8]) -> bool {
        let expected = self.mac_with(token, identity, request);
        expected
            .iter()
            .zip(self.mac)
            .fold(0u8, |acc, (a, b)| acc | (a ^ b))
            == 0
    }

    fn mac_with(&self, token: SessionToken, identity: &str, request: &[u8]) -> [u8; 16] {
        use hmac::{Mac as _, SimpleHmac};
        let mut mac = SimpleHmac::<sha3::Sha3_256>::new_from_slice(&token.0)
            .expect("HMAC takes a key of any length");
        mac.update(MAC_DOMAIN);
        mac.update(identity.as_bytes());
        mac.update(&[0]);
        mac.update(request);
        mac.update(&self.encode()[1..33]);
        let full = mac.finalize().into_bytes();
        let mut out = [0; 16];
        out.copy_from_slice(&full[..16]);
        out
    }

    /// The 49 bytes.
    pub fn encode(&self) -> [u8; 49] {
        let mut out = [0; 49];
        out[0] = CONTRACT_VERSION;
        out[1..17].copy_from_slice(&self.session.0.to_le_bytes());
        out[17..25].copy_from_slice(&self.counter.to_le_bytes());
        out[25..33].copy_from_slice(&self.sent_ns.to_le_bytes());
        out[33..49].copy_from_slice(&self.mac);
        out
    }

    /// From the attachment's bytes; `None` for another size or version.
    pub fn decode(bytes: &[u8]) -> Option<Self> {
        let bytes = <&[u8; 49]>::try_from(bytes).ok()?;
        if bytes[0] != CONTRACT_VERSION {
            return None;
        }
        Some(Self {
            session: SessionId(u128::from_le_bytes(bytes[1..17].try_into().ok()?)),
            counter: u64::from_le_bytes(bytes[17..25].try_into().ok()?),
            sent_ns: u64::from_le_bytes(bytes[25..33].try_into().ok()?),
            mac: bytes[33..49].try_into().ok()?,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The MAC of a known request, worked out independently of [`RequestMeta::sign`] (HMAC
    /// from its definition over SHA3-256, block 136 bytes): Python's
    /// `hmac.new(bytes([7]*16), msg, "sha3_256")` gives the same (python/tests/test_remote.py
    /// pins the same bytes).
    #[test]
    fn the_request_mac_is_hmac_sha3_256_of_the_documented_bytes() {
        use sha3::Digest as _;
        let token = SessionToken([7; 16]);
        let request: Vec<u8> = (0u8..64).collect();
        let meta = RequestMeta::sign(token, "panel", &request, SessionId(0x0102), 5, 1_000);
        let bytes = meta.encode();
        assert_eq!(bytes.len(), RequestMeta::SIZE);
        assert_eq!(bytes[0], 3);
        assert_eq!(&bytes[1..3], &[0x02, 0x01]);
        assert_eq!(&bytes[17..25], &5u64.to_le_bytes());
        assert_eq!(&bytes[25..33], &1_000u64.to_le_bytes());
        // HMAC by hand.
        let mut key = [0u8; 136];
        key[..16].copy_from_slice(&token.0);
        let pad = |byte: u8| key.iter().map(|k| k ^ byte).collect::<Vec<u8>>();
        let mut message = b"motiond-request-v3panel\0".to_vec();
        message.extend_from_slice(&request);
        message.extend_from_slice(&bytes[1..33]);
        let inner = sha3::Sha3_256::new()
            .chain_update(pad(0x36))
            .chain_update(&message)
            .finalize();
        let outer = sha3::Sha3_256::new()
            .chain_update(pad(0x5c))
            .chain_update(inner)
            .finalize();
        assert_eq!(&bytes[33..49], &outer[..16]);
        assert_eq!(
            hex(&bytes[33..49]),
            GOLDEN_MAC,
            "the golden MAC Python's test pins"
        );
        assert!(meta.verify(token, "panel", &request));
        // Another identity, request, counter or token: not the MAC.
        assert!(!meta.verify(token, "other", &request));
        let mut changed = request.clone();
        changed[8] ^= 1;
        assert!(!meta.verify(token, "panel", &changed));
        assert!(!meta.verify(SessionToken([8; 16]), "panel", &request));
        let replayed_later = RequestMeta { counter: 6, ..meta };
        assert!(!replayed_later.verify(token, "panel", &request));
        assert!(
            !format!("{meta:?}").contains("7, 7, 7"),
            "the secret is nowhere in it"
        );
    }

    /// The MAC of the test above, in hex (python/tests/test_remote.py has the same).
    const GOLDEN_MAC: &str = "e761b1d15721ac41efb5c765052e2456";

    fn hex(bytes: &[u8]) -> String {
        bytes.iter().map(|b| format!("{b:02x}")).collect()
    }

    #[test]
    fn attachments_round_trip_and_refuse_other_sizes() {
        let meta = RequestMeta::sign(SessionToken([7; 16]), "panel", &[1; 64], SessionId(9), 1, 2);
        let bytes = meta.encode();
        assert_eq!(bytes[0], 3);
        assert_eq!(RequestMeta::decode(&bytes), Some(meta));
        assert_eq!(RequestMeta::decode(&bytes[..48]), None);
        let mut other = bytes;
        other[0] = 2;
        assert_eq!(RequestMeta::decode(&other), None, "the old attachment");
        assert_eq!(
            RequestMeta::decode(&[2; 25]),
            None,
            "the old 25-byte attachment"
        );
        let none = RequestMeta::sessionless(77);
        assert_eq!(RequestMeta::decode(&none.encode()), Some(none));

        let open = SessionOpen::new(99, [3; 32], "a1b2c3");
        assert_eq!(open.zid(), Some("a1b2c3"));
        assert_eq!(SessionOpen::decode(&open.encode()), Some(open));
        assert_eq!(SessionOpen::decode(&open.encode()[..72]), None);
        assert_eq!(SessionOpen::new(1, [3; 32], "").zid(), None);
        assert_eq!(SessionOpen::decode(&[2; 9]), None, "the old opening");
        let grant = SessionGrant {
            session: SessionId(u128::MAX - 1),
            public: [0xa5; 32],
        };
        let bytes = grant.encode();
        assert_eq!(bytes.len(), SessionGrant::SIZE);
        assert_eq!(SessionGrant::decode(&bytes), Some(grant));
        let zero = SessionGrant {
            session: SessionId(0),
            ..grant
        };
        assert_eq!(SessionGrant::decode(&zero.encode()), None, "no zero id");
        assert_eq!(
            format!("{:?}", SessionToken([1; 16])),
            "SessionToken(…)",
            "never logged"
        );
    }

    /// Both sides agree on the session's secret from the two public keys; it is in neither
    /// message. Golden: the bridge's and the client's keys of bytes 1..=32 and 33..=64
    /// (python/tests/test_remote.py derives the same secret with `cryptography`'s X25519).
    #[test]
    fn both_sides_agree_on_a_secret_that_never_travels() {
        let client = KeyPair::from_random(core::array::from_fn(|i| i as u8 + 1));
        let bridge = KeyPair::from_random(core::array::from_fn(|i| i as u8 + 33));
        let session = SessionId(0x0102);
        let open = SessionOpen::new(5, client.public(), "c0ffee");
        let grant = SessionGrant {
            session,
            public: bridge.public(),
        };
        let on_client = client.agree(client.public(), grant.public, session);
        let on_bridge = bridge.agree(open.public, bridge.public(), session);
        assert!(on_client.is_some());
        assert_eq!(on_client, on_bridge);
        let token = on_client.expect("agreed");
        assert_eq!(hex(&token.0), GOLDEN_SECRET);
        for message in [&open.encode()[..], &grant.encode()[..]] {
            assert!(
                !message.windows(16).any(|window| window == token.0),
                "the secret is in a message"
            );
        }
        // Another session id: another secret; a key of all zeros (a low-order point): none.
        assert_ne!(
            client.agree(client.public(), grant.public, SessionId(3)),
            on_client
        );
        assert_eq!(bridge.agree([0; 32], bridge.public(), session), None);
    }

    /// The secret of the test above, in hex.
    const GOLDEN_SECRET: &str = "8b426f0d029361820a9f12a653f823b0";
}
