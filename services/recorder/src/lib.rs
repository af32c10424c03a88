//! MCAP recordings of taut's samples.
//!
//! The file layout is fixed by [`format`] (topics, schemas, encodings, metadata) so that the
//! recorder service, `taut sim --fast`, `taut report` and `taut replay` all agree; [`read`]
//! loads a recording (a complete one, or one cut short by a crash) into typed samples.

pub mod format;
pub mod read;

pub use format::{channel_topic, Recordable};
pub use read::{ReadError, Recording, Timed};
