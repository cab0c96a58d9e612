"""``run_benchmark`` on a world file: the lab's house B (skipped without ../shared), reported apart."""

import json

import pytest

from tests.sim.test_sim_real_house_world import SHARED, write_real_world

pytestmark = [pytest.mark.shared_data, pytest.mark.slow,
              pytest.mark.skipif(not SHARED.is_dir(), reason="../shared/data/mapir_house_B is absent")]


def test_benchmark_on_the_lab_house(tmp_path):
    from psgsl_pgm.search import SearchConfig
    from psgsl_pgm.search._benchmark import run_benchmark

    world = write_real_world(tmp_path)
    out = tmp_path / "b"
    summary = run_benchmark(out=out, world=world, seeds=2, policies=("greedy", "semantic-modes"),
                            variants=("olfaction", "semantics+rooms"), conditions=("right-ontology", "no-rooms"),
                            search=SearchConfig(time_budget=30.0), workers=1, progress=False, figures=False)
    assert summary["settings"]["houses"] == ["world"] and summary["settings"]["world"] == str(world.resolve())
    runs = sorted(p.name for p in (out / "runs").iterdir())
    # per seed: right (greedy ×2, semantic-modes) + no-rooms (greedy/semantics+rooms, semantic-modes) = 5 runs
    assert len(runs) == 2 * 5 and all(r.startswith("world__") for r in runs)
    report = (out / "report.md").read_text()
    assert report.startswith(f"# psgsl benchmark: world file {world.resolve()}")
    episodes = json.loads((out / "episodes.json").read_text())
    assert set(episodes) == {"world/0", "world/1"}
    # the no-rooms world names the lab's files and an ontology without p(o | room)
    from psgsl_pgm.sim import load_world

    bare = load_world(out / "worlds" / "world__no-rooms.yaml")
    assert bare.ontology.rooms == () and bare.ontology.classes == load_world(world).ontology.classes


@pytest.mark.parametrize(("policy", "seed"), [("semantic-modes", 1), ("greedy", 3)])
def test_target_policies_drive_to_a_reachable_cell_nearest_their_target(tmp_path, policy, seed):
    """House B's microwave: a target (a mode of p(s | z), the MAP cell) whose nearest drivable cell lies in another
    component of the free space. Steering towards that cell had the robot shuttle between two stops until the
    budget; the reachable drivable cell nearest the target is a stop it can reach, and it finds the microwave."""
    from psgsl_pgm.runs._key import digest, world_key
    from psgsl_pgm.search import SearchConfig
    from psgsl_pgm.search._grid import closed_loop_in_world
    from psgsl_pgm.sim import load_world

    world = write_real_world(tmp_path)
    house = load_world(world).house(0)
    microwave = next(o for o in house.objects if o.name == "microwave_1")
    run = closed_loop_in_world(tuple(microwave.center), seed, policy, "semantics+rooms", "infotaxis",
                               world=str(world), world_digest=digest(world_key(world)),
                               search=SearchConfig(time_budget=300.0))
    assert run.found and run.time_to_find < 300.0
    distinct = {tuple(p) for p in run.position.round(2).tolist()}
    assert len(distinct) > len(run.position) // 2  # no stop visited over and over
