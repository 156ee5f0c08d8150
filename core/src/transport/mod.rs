//! Light transport shared by every estimator: the one bounce loop ([`walk`]).

pub mod walk;
