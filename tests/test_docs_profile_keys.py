"""``docs/NEW_ROBOT.md`` names every key a robot profile may have, as the profile reader itself lists
them."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


#: A key added to a profile table to make the reader list the table's keys in its refusal.
PROBE = "zz_probe"
#: The tables whose keys are names the profile chooses (joints, plants): not probed.
FREE_TABLES = ("model.stand.joints", "plants")


def _keys_listed(message: str) -> list[str]:
    """The keys an "unknown key" refusal lists: ``(known: a, b)``, ``(known here: a, b)`` or ``a table of a, b``."""
    m = re.search(r"\(known(?: here)?: ([^)]*)\)", message) or re.search(r"must be a table of (.*)$", message)
    return [k.strip() for k in m.group(1).split(",")] if m else []


def profile_keys(tmp_path: Path) -> dict[str, set[str]]:
    """Table (``""`` for the top level, ``"model.stand"``, ``"trackers.qp"`` ...) -> every key the
    profile reader accepts in it, as the reader itself lists them: a probe key added to each table of
    each bundled profile is refused with the list of the table's keys (the tracker tables when the
    tracker's configuration is built)."""
    from amlip_qp.estimation.invariant_ekf import noise_from_table
    from amlip_qp.exceptions import InputError
    from amlip_qp.paths import MODELS_DIR
    from amlip_qp.profiles import bundled_names, read_profile
    from amlip_qp.sim.scenarios.scenario_tables import profile_scenarios

    found: dict[str, set[str]] = {}
    for name in bundled_names():
        text = (MODELS_DIR / f"{name}.toml").read_text()
        text = re.sub(r'"([^"]+\.xml)"', lambda m: f'"{(MODELS_DIR / m.group(1)).resolve()}"', text)
        tables = [t for t in re.findall(r"^\[([\w.]+)\]$", text, re.M) if t not in FREE_TABLES]
        probes = {"": f"{PROBE} = 1\n{text}", "trackers": f"{text}\n[trackers.{PROBE}]\n"}
        for table in tables:
            probes[table] = text.replace(f"[{table}]\n", f"[{table}]\n{PROBE} = 1\n", 1)
        for table, probed in probes.items():
            path = tmp_path / f"{name}-{table or 'top'}.toml"
            path.write_text(probed)
            try:
                profile = read_profile(path)
                if table.split(".")[0] in ("scenarios", "settings", "mismatches"):
                    profile_scenarios(profile)  # these tables are checked when the scenarios are built
                elif table == "estimator":
                    noise_from_table(profile.estimator)
                else:
                    tracker = table.split(".")[1] if table.startswith("trackers.") else None
                    assert tracker is not None, f"{table}: the probe key was accepted"
                    profile.tracker_config(tracker)
                raise AssertionError(f"{table}: the probe key was accepted")
            except InputError as exc:
                keys = _keys_listed(str(exc))
                assert keys, f"{table}: no key list in {exc}"
                table = re.sub(r"^(scenarios|settings)\..*", r"\1.KEY", table)  # one entry per kind
                found.setdefault(table, set()).update(keys)
    return found


def test_the_new_robot_guide_names_every_profile_key(tmp_path):
    keys = profile_keys(tmp_path)
    tables = {"", "model", "model.stand", "roles", "feet", "imu", "gait", "bounds", "verified", "shaping", "compare"}
    tables |= {"trackers", "trackers.qp", "trackers.pbc", "trackers.pbc.spring_model_linkage"}
    tables |= {"scenarios.KEY", "settings.KEY", "mismatches", "estimator"}
    assert set(keys) == tables  # each table was probed, in some bundled profile (none has [unsupported])
    assert sum(len(k) for k in keys.values()) > 90
    assert {"step_time_s", "servos", "passive_in_stance", "pos_m", "quat_wxyz"} <= set().union(*keys.values())
    text = (ROOT / "docs" / "NEW_ROBOT.md").read_text()
    missing = [
        f"[{table}] {key}" if table else key
        for table, names in sorted(keys.items())
        for key in sorted(names)
        if f"`{key}`" not in text and f"[{table + '.' if table else ''}{key}]" not in text
    ]
    missing += [f"[{table}]" for table in sorted(keys) if table and f"[{table}]" not in text]
    assert missing == []
