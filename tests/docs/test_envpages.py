"""The env pages (docs/envs/) are generated from the code: cards, registry, observation names."""

from __future__ import annotations

import dataclasses
import re

import envpages
import gymnasium as gym
import pytest

import softgrasp_env
from softgrasp_env import arguments, registration
from softgrasp_env.env import SoftGraspEnv, SoftGraspGoalEnv


@pytest.fixture(scope="module")
def pages() -> dict[str, str]:
    return envpages.render_pages()


def _ids_on(text: str) -> set[str]:
    return set(re.findall(r"`(SoftGrasp[A-Za-z]*-v\d+)`", text))


def test_every_registered_id_is_on_exactly_one_family_page(pages):
    families = {name: text for name, text in pages.items() if name != "index.md"}
    assert set(families) >= {"lift.md", "goal.md", "grip.md"}
    for env_id in softgrasp_env.ENV_IDS:
        # the page's Registered ids table lists it (a card's prose may mention other ids)
        holders = [name for name, text in families.items() if f"| `{env_id}` |" in text]
        assert len(holders) == 1, (env_id, holders)
    grouping = {fam.key: fam.ids for fam in envpages.families().values()}
    assert sorted(i for ids in grouping.values() for i in ids) == sorted(softgrasp_env.ENV_IDS)
    assert all(i.startswith("SoftGraspGoal-") for i in grouping["goal"])
    assert all(i.startswith("SoftGraspGrip") for i in grouping["grip"])
    assert "SoftGrasp-v5" in grouping["lift"]
    # the index links every family and names every id
    assert _ids_on(pages["index.md"]) == set(softgrasp_env.ENV_IDS)


def test_every_observation_name_is_on_its_page(pages):
    for fam in envpages.families().values():
        text = pages[f"{fam.key}.md"]
        for env_id in fam.ids:
            names = envpages.env_plan(env_id).obs_names
            assert names, env_id
            missing = [n for n in names if f"`{n}`" not in text]
            assert not missing, (env_id, missing[:5])


def test_pages_have_gymnasiums_sections(pages):
    for name in ("lift.md", "goal.md", "grip.md"):
        headings = re.findall(r"^## (.+)$", pages[name], flags=re.M)
        for section in ("Description", "Action Space", "Observation Space", "Rewards", "Starting State",
                        "Episode End", "Arguments", "Version History"):  # fmt: skip
            assert section in headings, (name, section)
            body = pages[name].split(f"## {section}\n", 1)[1].split("\n## ", 1)[0]
            assert body.strip(), (name, section)
    # the versions registered, generated from the registry
    for env_id in softgrasp_env.ENV_IDS:
        name, version = envpages.split_id(env_id)
        page = pages[f"{envpages.family_of(env_id)}.md"]
        assert re.search(rf"- `{name}`: [^\n]*\b{version}\b", page), env_id


def test_a_changed_card_section_changes_the_page(monkeypatch):
    marker = "The cylinder is painted bright orange for this test."
    doc = SoftGraspEnv.__doc__.replace("## Starting state\n", f"## Starting state\n    {marker}\n", 1)
    assert marker in doc
    before = envpages.render_pages()
    assert marker not in before["lift.md"]
    monkeypatch.setattr(SoftGraspEnv, "__doc__", doc)
    after = envpages.render_pages()
    section = after["lift.md"].split("## Starting State\n", 1)[1].split("\n## ", 1)[0]
    assert marker in section
    assert marker in after["grip.md"] and marker in after["goal.md"]  # both build on SoftGraspEnv's card


def test_a_changed_goal_card_changes_the_goal_page(monkeypatch):
    marker = "compute_reward pays a bonus in this test"
    doc = SoftGraspGoalEnv.__doc__.replace("## Rewards\n", f"## Rewards\n    {marker}.\n", 1)
    assert marker in doc
    monkeypatch.setattr(SoftGraspGoalEnv, "__doc__", doc)
    page = envpages.render_pages()["goal.md"]
    rewards = page.split("## Rewards\n", 1)[1].split("\n## ", 1)[0]
    assert marker in rewards
    assert "success_height" not in rewards  # the goal's reward replaces the lift card's


def test_the_goal_card_has_gymnasiums_sections_of_its_own():
    """The goal card's own ## sections lead its page's sections, the lift card's follow."""
    _, sections = envpages.split_sections(envpages.card_text(SoftGraspGoalEnv))
    for key in ("description", "observation space", "rewards", "starting state", "episode end", "arguments",
                "version history"):  # fmt: skip
        assert sections.get(key), key
    page = envpages.render_pages()["goal.md"]
    episode_end = page.split("## Episode End\n", 1)[1].split("\n## ", 1)[0]
    assert episode_end.index("end_when_knocked_over") < episode_end.index("The lift family's card")
    history = page.split("## Version History\n", 1)[1]
    assert "- v4:" in history and "- v3:" in history


def test_the_grip_force_section_is_on_the_grip_page_only(pages):
    _, sections = envpages.split_sections(envpages.card_text(SoftGraspEnv))
    assert "grip-force task" in sections
    grip = pages["grip.md"]
    assert "## Grip-force task" in grip
    assert grip.index("## Grip-force task") < grip.index("## Action Space")
    assert "## Grip-force task" not in pages["lift.md"] and "## Grip-force task" not in pages["goal.md"]
    # every version of the task is on it, whatever its charge, and on no other page
    grip_ids = [i for i in registration.ENV_IDS if i.startswith("SoftGraspGrip")]
    assert len(grip_ids) == 6
    for env_id in grip_ids:
        assert f"| `{env_id}` |" in grip and f"| `{env_id}` |" not in pages["lift.md"], env_id


def test_a_changed_argument_changes_the_arguments_table(monkeypatch):
    """The table is made from the keywords' table (``arguments.KEYWORDS``) at build time, not the
    docstring's copy."""
    new_doc = "Weight of the reach term, changed by this test"
    keywords = tuple(dataclasses.replace(k, doc=new_doc) if k.name == "reach_weight" else k
                     for k in arguments.KEYWORDS)  # fmt: skip
    monkeypatch.setattr(arguments, "KEYWORDS", keywords)
    page = envpages.render_pages()["lift.md"]
    section = page.split("## Arguments\n", 1)[1].split("\n## ", 1)[0]
    assert f"| `reach_weight` | float | `0.1` | {new_doc} |" in section
    assert "Weight of the reach shaping term" not in section


def test_a_new_registered_id_gets_onto_its_page(monkeypatch):
    """A grip-task id registered tomorrow lands on the grip page, with its version line."""
    env_id = "SoftGraspGripTest-v9"
    kwargs = {"fingers": "rigid", "reward_type": "dense", "start": "easy", "carry": True, **registration.GRIP_TASK}
    gym.register(id=env_id, entry_point="softgrasp_env.env:SoftGraspEnv", kwargs=kwargs, max_episode_steps=100)
    try:
        monkeypatch.setattr(registration, "ENV_IDS", (*registration.ENV_IDS, env_id))
        pages = envpages.render_pages()
        assert f"| `{env_id}` |" in pages["grip.md"]
        assert "- `SoftGraspGripTest`: v9" in pages["grip.md"]
        assert env_id not in pages["lift.md"]
    finally:
        del gym.registry[env_id]


def test_write_pages_writes_each_family_and_removes_stale_ones(tmp_path):
    (tmp_path / "gone.md").write_text("# a family no longer registered")
    written = envpages.write_pages(tmp_path)
    assert {p.name for p in written} == {p.name for p in tmp_path.glob("*.md")}
    assert not (tmp_path / "gone.md").exists()
    assert (tmp_path / "lift.md").read_text().startswith("# Lift family")
