//! `corrugation` command-line interface.
fn main() {
    println!("corrugation {}", env!("CARGO_PKG_VERSION"));
}
