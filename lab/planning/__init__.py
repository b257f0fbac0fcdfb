"""Planning benchmarks: the shipped problem sets, Nav2's real maps, and the referee that judges both."""
