"""The run tables docs/results/ reports, rendered from runs' metrics.json files."""

import json

from cli import run_script


def write_run(folder, name, metrics):
    (folder / name).mkdir(parents=True)
    (folder / name / "metrics.json").write_text(json.dumps(metrics))


def final(catch_rate, throws, up):
    episode = {"throws": throws}
    return {
        "catch_rate": catch_rate,
        "mean_throws": throws,
        "mean_time_to_drop": up,
        "duration": 120.0,
        "episodes": [episode] * 5,
    }


def test_the_offpolicy_table_groups_seeds_by_algorithm_reward_and_actor(tmp_path):
    base = {"reward": "distance", "actor": "mlp", "frames": 307200}
    write_run(
        tmp_path,
        "a",
        {
            **base,
            "algo": "ddpg",
            "seed": 0,
            "wall_seconds": 300,
            "final_evaluation": final(1.0, 0.0, 120.0),
        },
    )
    write_run(
        tmp_path,
        "b",
        {
            **base,
            "algo": "ddpg",
            "seed": 1,
            "wall_seconds": 420,
            "final_evaluation": final(0.0, 2.0, 1.0),
        },
    )
    write_run(
        tmp_path,
        "c",
        {
            **base,
            "algo": "td3",
            "seed": 0,
            "wall_seconds": 360,
            "final_evaluation": final(0.0, 0.0, 3.0),
        },
    )
    result = run_script("offpolicy_table.py", str(tmp_path))
    assert result.returncode == 0, result.stderr
    lines = result.stdout.strip().splitlines()
    assert lines[2] == (
        "| `ddpg` | `distance` | `mlp` | 0,1 | 50% (of 10) | 1.0 | 60.5 of 120 | 307,200 | 6.0 |"
    )
    assert lines[3].startswith("| `td3` | `distance` | `mlp` | 0 | 0% (of 5) |")


def test_a_folder_without_runs_gives_one_error_line(tmp_path):
    result = run_script("dps_table.py", str(tmp_path))
    assert result.returncode != 0
    assert result.stderr.strip() == f"error: no search metrics.json below {tmp_path}"
