//! Test helpers shared by the unit tests of this crate: the synthetic P300 epochs live in the
//! workspace's test-kit (one copy for unit and integration tests).

pub(crate) use oddball_testkit::synthetic_p300;
