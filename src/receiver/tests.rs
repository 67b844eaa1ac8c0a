//! Receiver tests: cold start to fine attitude, faults.
