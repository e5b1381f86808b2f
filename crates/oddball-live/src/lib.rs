//! Live operation of the oddball BCI: a session against a live EEG stream with a stimulus panel
//! a person looks at, recorded to disk as it runs.
//!
//! * [`panel`]: the stimulus panel, a web page served by the binary, live over a WebSocket;
//!   each view only for its session's pages (a key per view, `Host` and `Origin` checked).
//! * [`listen`]: every listener, loopback only unless remote connections are allowed.
//! * [`live`]: the live session's subject: a live EEG source, the panel, the marker stream and
//!   the recording on one clock; the simulated subject as a live source.
//! * [`clock`]: the session clock (ms) the panel, the sources and the recording share, and the
//!   one [`clock::Pacer`] that paces simulated and played-back EEG by it.
//! * [`decode`]: `oddball decode`, the online decoder behind another program's stimuli: EEG
//!   from any source, the program's markers over LSL, decisions out as JSON.
//! * [`source`]: every live source behind one type, as `--source` names it
//!   (`sim`, `nic:HOST:PORT`, `lsl:NAME`, `replay:FILE`).
//! * [`nic`]: Neuroelectrics NIC's TCP stream as a live source (reconnecting), and a simulated
//!   Starstim serving one; the byte codec is `oddball_io::nic`.
//! * [`online`]: what `oddball online` reports of a live session (`summary.json`, its lines).
//! * [`plan`]: a live session assembled from its plan (source, open options, settings, start,
//!   montage, arm), checked, opened and started: what every front end runs.
//! * [`pilot`]: the calibrated pilot of `demo` and `task` (a live session or a replayed
//!   recording) and what its run leaves behind.
//! * [`playback`]: a recording played back as a live source (`--source replay:FILE`).
//! * [`record`]: the recording, XDF flushed per block.
//! * [`lsl`]: Lab Streaming Layer inlets and outlets (EEG in, markers and decisions out) over
//!   liblsl loaded at run time (in every build; an error says how to get liblsl when it is
//!   missing), LSL as a live source ([`lsl_live`]) and the simulated subject as a live LSL
//!   amplifier ([`lsl_sim`]).
//!
//! # Example
//! The timing report's summary of a list of delays (population standard deviation):
//! ```
//! use oddball_live::timing::Summary;
//!
//! let s = Summary::of(&[1.0, 2.0, 3.0, 6.0]).unwrap();
//! assert_eq!((s.n, s.mean, s.min, s.max), (4, 3.0, 1.0, 6.0));
//! assert!((s.sd - 1.8708286933869707).abs() < 1e-15);
//! assert_eq!(Summary::of(&[]), None);
//! ```

pub mod clock;
pub mod decode;
mod error;
pub mod listen;
pub mod live;
pub mod lsl;
pub mod lsl_live;
pub mod lsl_sim;
pub mod nic;
pub mod online;
pub mod panel;
pub mod pilot;
pub mod plan;
pub mod playback;
pub mod record;
pub mod sim;
pub mod source;
pub mod stop;
pub mod timing;

pub use error::LiveError;
