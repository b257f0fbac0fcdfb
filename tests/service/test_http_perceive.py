"""``POST /v1/perceive``: the same JSON as ``sphereplan perceive`` for the same pair; bad parts are 4xx naming them.

The app runs in-process over a thread pool (no worker processes), which is all this route needs.
"""

from __future__ import annotations

import base64
import json
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient

from lab.perception_render import obstacle_course, render_pair, write_pair
from service.cli import main
from service.core import PlanningService
from service.http import create_app
from service.settings import ServiceSettings


@pytest.fixture(scope="module")
def pair_files(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    return write_pair(render_pair(obstacle_course(), 270, 206, supersample=1), tmp_path_factory.mktemp("pair"))


@pytest.fixture(scope="module")
def client() -> Iterator[TestClient]:
    settings = ServiceSettings(zenoh=False, warm_up=False, workers=1)
    service = PlanningService(settings, executor_factory=lambda n: ThreadPoolExecutor(n))
    with TestClient(create_app(settings, service)) as c:
        yield c


def body(files: dict[str, Path], **changes: Any) -> dict[str, Any]:
    import yaml

    out = {"left_image": base64.b64encode(files["left_png"].read_bytes()).decode(),
           "right_image": base64.b64encode(files["right_png"].read_bytes()).decode(),
           "left_info": yaml.safe_load(files["left_yaml"].read_text()),
           "right_info": yaml.safe_load(files["right_yaml"].read_text()),
           "pose": {"x": 1.0, "y": -2.0, "yaw_deg": 20.0}, "roll": 3.0, "degrees": True}
    out.update(changes)
    return out


def without_timings(result: dict[str, Any]) -> dict[str, Any]:
    return {k: v for k, v in result.items() if k != "timings_s"}


def test_perceive_equals_cli(client: TestClient, pair_files: dict[str, Path], tmp_path: Path,
                             capsys: pytest.CaptureFixture[str]) -> None:
    response = client.post("/v1/perceive", json=body(pair_files))
    assert response.status_code == 200, response.text
    result = response.json()
    assert result["count"] > 50 and len(result["points_map"]) == result["count"]
    code = main(["perceive", "--left", str(pair_files["left_png"]), "--right", str(pair_files["right_png"]),
                 "--left-info", str(pair_files["left_yaml"]), "--right-info", str(pair_files["right_yaml"]),
                 "--pose", "1", "-2", "20", "--roll", "3", "--degrees", "-q"])
    assert code == 0
    assert without_timings(json.loads(capsys.readouterr().out)) == without_timings(result)


@pytest.mark.parametrize("changes, status, field", [
    ({"right_image": base64.b64encode(b"not an image").decode()}, 422, "right_image"),
    ({"left_image": "***"}, 422, "left_image"),
    ({"left_info": {"image_width": 270}}, 422, "left_info"),
    ({"pose": {"x": 0.0, "y": 0.0, "yaw": 7.0}, "degrees": False}, 422, "pose.yaw"),
    ({"roll": 9.0, "pose": {"x": 0.0, "y": 0.0, "yaw": 0.0}, "degrees": False}, 422, "roll"),
    ({"robot": "nobody"}, 404, "robot"),
])
def test_bad_parts_are_4xx_naming_them(client: TestClient, pair_files: dict[str, Path], changes: dict[str, Any],
                                       status: int, field: str) -> None:
    response = client.post("/v1/perceive", json=body(pair_files, **changes))
    assert response.status_code == status, response.text
    assert response.json()["field"] == field


def test_mismatched_sizes_name_the_right_image(client: TestClient, pair_files: dict[str, Path],
                                               tmp_path: Path) -> None:
    from PIL import Image

    small = tmp_path / "small.png"
    Image.open(pair_files["right_png"]).crop((0, 0, 200, 206)).save(small)
    response = client.post("/v1/perceive", json=body({**pair_files, "right_png": small}))
    assert response.status_code == 422 and response.json()["field"] == "right_image"
    assert "mismatched image sizes" in response.json()["error_msg"]


def test_nan_is_refused_before_any_work(client: TestClient, pair_files: dict[str, Path]) -> None:
    text = json.dumps(body(pair_files)).replace('"roll": 3.0', '"roll": NaN')
    response = client.post("/v1/perceive", content=text, headers={"content-type": "application/json"})
    assert 400 <= response.status_code < 500
