//! The simulated world: the [`robot`] model, its [`physics`] engines, the dynamics
//! [`profile`] a policy is deployed under, the reference [`motion`]s it tracks, the hand
//! forces [`replay`]ed on it or the [`disturbance`]s put on it instead, what its [`feet`]
//! do on the ground, and open-loop [`scenario`]s that drive it without a policy.

pub mod disturbance;
pub mod feet;
pub mod motion;
pub mod physics;
pub mod profile;
pub mod replay;
pub mod robot;
pub mod scenario;
