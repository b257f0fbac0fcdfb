"""After ``warm_up`` no plan compiles a kernel: its time limit is the search's own (issue 21, ninth round: a plan
on bays that first shot from Python, as the goal side's searches do, spent a second compiling ``try_shot``)."""

import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[3]

SCRIPT = r"""
import sys
import numba.core.dispatcher as dispatcher
from planner.hybrid_astar import search
from planner.maps.load import load_map
from planner.robot import load_robot
from tests.scenarios import SCENARIO_BINS

search.warm_up()
compiled = []
original = dispatcher.Dispatcher._compile_for_args
def record(self, *args, **kwargs):
    compiled.append(f"{self.py_func.__module__}.{self.py_func.__name__}")
    return original(self, *args, **kwargs)
dispatcher.Dispatcher._compile_for_args = record
robot = load_robot("zju-60")
for name, start, goal, mark in (
    # the goal side's search closes a gap to the start's tree with a shot (two_ended), and the fallback shot
    ("bays", (12.675, 6.875, 1.7956445157270178), (16.725, 11.575, 2.7147110747537946), "fallback_shot_taken"),
    # a turn between the two trees (two_ended.GoalSide._turn)
    ("pockets", (18.675, 13.375, 0.7312609262013985), (23.025, 17.175, 2.609458811313899), "turn_searches"),
    # a held shot that costs less than the path found meanwhile
    ("depot", (16.875, 2.725, -0.7051674435222814), (23.475, 10.275, 0.6605926729954539), "held_shot_taken"),
    # the forward-only alternative search, and the anytime rounds
    ("depot", (26.025, 9.575, 0.06727095832306862), (10.625, 9.575, 3.1096574102329626),
     "forward_alternative_expansions"),
    ("bays", (22.575, 9.425, -1.3479617223735876), (17.575, 8.225, -0.3594680053165016), "improvements"),
):
    # (scenarios found with 72 heading bins, the default until issue 21's twelfth round: tests.scenarios)
    options = search.PlannerOptions(improve_until_s=0.3 if mark == "improvements" else 0.0,
                                    n_yaw_bins=SCENARIO_BINS)
    result = search.HybridAStar(load_map(f"maps/real/{name}.yaml"), robot, options).plan(start, goal)
    assert result.extra.get(mark), (name, mark)
print("compiled:", ",".join(compiled))
"""


def test_no_plan_compiles_after_warm_up() -> None:
    out = subprocess.run([sys.executable, "-c", SCRIPT], cwd=REPO, capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.strip().splitlines()[-1] == "compiled:", out.stdout
