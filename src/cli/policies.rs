//! `thorarena policies`: every policy family a run can name, what a user supplies for it,
//! the profile it runs under when `--profile` is not given, and where it runs.

use thorarena::registry::{Runs, KNOWN_NETWORKS, POLICY_FAMILIES};

pub(super) fn run() -> anyhow::Result<()> {
    println!("| --policy | what it is | you supply | profile by default | runs |");
    println!("|---|---|---|---|---|");
    for f in &POLICY_FAMILIES {
        let runs = match f.runs {
            Runs::InProcess => "in process",
            Runs::OwnProcess => "its own process",
        };
        println!(
            "| `{}` | {} | {} | `{}` | {runs} |",
            f.spelling, f.what, f.supplies, f.profile
        );
    }
    println!("\nPublished networks known by content (SHA-256): each runs under its own profile when no --profile is named, whatever the file is called.\n");
    println!("| file | profile | source |");
    println!("|---|---|---|");
    for n in &KNOWN_NETWORKS {
        println!("| `{}` | `{}` | {} |", n.file, n.profile, n.source);
    }
    println!(
        "\nProfiles: data/profiles/*.toml (or a .toml path with --profile); `client` runs a built-in as a policy process."
    );
    Ok(())
}
