//! MCAP recordings of taut's samples.
//!
//! The file layout is fixed by [`format`] (topics, schemas, encodings, metadata) so that the
//! recorder service, `taut sim --fast`, `taut report` and `taut replay` all agree; [`write`]
//! writes it (the service and fast mode), [`read`] loads a recording (a complete one, or one cut
//! short by a crash) into typed samples, and [`shell`] is the recorder service.

pub mod format;
pub mod read;
pub mod shell;
mod stats;
pub mod write;

pub use format::{channel_topic, Recordable};
pub use read::{ReadError, Recording, Timed};
pub use write::{
    ChannelHandle, ChannelStats, CreateError, Mode, RecordingInfo, RecordingWriter, WriteError,
};
