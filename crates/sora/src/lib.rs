pub use sora_mie as mie;
