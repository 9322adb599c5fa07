"""Plant names and paths: which MJCF file ``--plant`` means."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from amlip_qp.exceptions import InputError, ModelFileError
from amlip_qp.paths import MODELS_DIR
from amlip_qp.sim.scenarios import factory
from amlip_qp.sim.world.plant_files import plant_files, resolve_plant_source


@pytest.fixture(scope="module")
def cassie():
    return factory.load("cassie")


def test_a_robots_plants_are_its_profiles_files(cassie):
    files = plant_files(cassie)
    assert files == {"cassie": MODELS_DIR / "cassie.xml", "cassie-closed-chain": MODELS_DIR / "cassie-closed-chain.xml"}
    assert all(path.is_file() for path in files.values())
    assert resolve_plant_source("cassie-closed-chain", cassie) == (
        "cassie-closed-chain",
        (MODELS_DIR / "cassie-closed-chain.xml").resolve(),
    )


def test_a_path_is_named_by_itself(cassie, tmp_path, monkeypatch):
    model = tmp_path / "mine.xml"
    model.write_text("<mujoco/>")
    assert resolve_plant_source(str(model), cassie) == (str(model), model.resolve())
    assert resolve_plant_source(model, cassie) == (str(model), model.resolve())  # a PathLike
    monkeypatch.setenv("HOME", str(tmp_path))
    assert resolve_plant_source("~/mine.xml", cassie) == (str(model), model.resolve())
    (tmp_path / "sub").mkdir()
    no_suffix = tmp_path / "sub" / "plant"  # a separator makes it a path, whatever its suffix
    no_suffix.write_text("<mujoco/>")
    assert resolve_plant_source(str(no_suffix), cassie)[1] == no_suffix.resolve()


def test_unknown_names_and_missing_files_say_what_to_fix(cassie, tmp_path):
    with pytest.raises(InputError, match="unknown plant 'moon' for cassie: known plants are cassie, cassie-closed"):
        resolve_plant_source("moon", cassie)
    with pytest.raises(ModelFileError, match="plant model file not found: .*none.xml"):
        resolve_plant_source(str(tmp_path / "none.xml"), cassie)
    with pytest.raises(ModelFileError):
        resolve_plant_source(Path(tmp_path / "none"), cassie)


def test_a_robot_without_a_profile_has_its_own_file(cassie):
    own = dataclasses.replace(cassie, profile=None)
    assert plant_files(own) == {"cassie": Path(cassie.path)}
    assert resolve_plant_source("cassie", own) == ("cassie", Path(cassie.path).resolve())
