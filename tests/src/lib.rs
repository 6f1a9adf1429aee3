//! Integration tests that start restauro's real binaries (coordinator, workers, client) on
//! loopback: bit-identity against the in-process render, fault injection, authentication.
//! They arrive with the cluster issue; the command-line tests of `restauro color` live beside
//! the client, in `client/tests/`.
