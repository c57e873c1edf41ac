//! The nested dissection's node order of a mesh, one node a line as its
//! coordinates "x y" (17 significant digits), for `bench/separators.py`,
//! which compares its fill with METIS's.
//!
//!     cargo run --release -p stickslip-fem --example dissection_nodes -- MESH OUT

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [mesh, out] = &args[..] else {
        eprintln!("usage: dissection_nodes MESH OUT");
        std::process::exit(2);
    };
    let mesh = stickslip_mesh::Mesh::from_file(mesh).unwrap_or_else(|e| {
        eprintln!("{e}");
        std::process::exit(2)
    });
    let order = stickslip_fem::ordering::dissection_nodes(&mesh);
    let text: String = order
        .nodes()
        .iter()
        .map(|&v| format!("{:.17e} {:.17e}\n", mesh.nodes[v][0], mesh.nodes[v][1]))
        .collect();
    std::fs::write(out, text).unwrap_or_else(|e| {
        eprintln!("{out}: {e}");
        std::process::exit(2)
    });
}
