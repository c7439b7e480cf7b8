//! What the tests and tools measure with: statistics ([`stats`]), image comparison
//! ([`compare`]), error-against-time curves ([`curve`]) and their charts ([`chart`]), and the
//! `bench` subcommand ([`bench`]).

pub mod bench;
pub mod chart;
pub mod compare;
pub mod curve;
pub mod stats;
