//! `data list`: the datasets the binary carries, by the name `--dataset` takes.

pub(super) fn run() -> anyhow::Result<()> {
    let robot = thorarena::policy::registry::robot("g1_29dof")?;
    for b in thorarena::sim::motion::bundled_datasets(&robot)? {
        let (n, hash) = (b.dataset.len(), b.dataset.content_hash());
        println!(
            "{:<11} {n:>3} sequences, content {}: {}",
            b.name,
            &hash[..16],
            b.what
        );
    }
    println!("(`thorarena data info NAME` describes one; `--dataset NAME` runs on it)");
    Ok(())
}
