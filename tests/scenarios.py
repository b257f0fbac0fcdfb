"""Settings some tests' scenarios were found with.

SCENARIO_BINS: heading bins (72, 5°), the planner's default until issue 21's twelfth round made it 36. Tests whose
real-map problems or crafted maps were found with 72 bins keep them (with 36 the search reaches most of those goals
without the mechanism the test is about: a held shot, a fallback, a join or turn between the trees, the forward
check, the anytime rounds)."""

SCENARIO_BINS = 72
