"""What the benchmarks run: named scenarios and task sets (the TOML files beside the package) and
the policy specs."""
