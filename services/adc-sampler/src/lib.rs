pub mod mcp3423;
pub mod sampler;

pub use sampler::{Clock, Sampler, SamplerCounters, SamplerSettings};
