"""The env pages (docs/envs/), generated from the code at build time so page and code cannot drift.

One page per env family, in Gymnasium's env-page form (description, action space, observation space,
rewards, starting state, episode end, arguments, version history). The sources:

- the env cards, the class docstrings of ``SoftGraspEnv`` and ``SoftGraspGoalEnv``
  (softgrasp_env/env.py), split at their ``## `` headings; the argument table is regenerated from
  ``softgrasp_env.arguments.argument_table()`` (the keywords' table, ``KEYWORDS``) on every build;
  a lift-card section that belongs to some families (``FAMILY_SECTIONS``: the grip-force task,
  the object set) goes on those families' pages only;
- the registered ids and their keywords (``softgrasp_env.registration.ENV_IDS``, gymnasium's
  registry): which family each id is in, the registered-ids table, the versions;
- the observation names (``EnvPlan.of(args).obs_names``, built from softgrasp_env/observation.py's
  ``OBS_GROUPS``): every entry of every id's observation, by index.

``write_pages(folder)`` writes them (a test calls it); as a Sphinx extension the pages are written
into the source tree's ``envs/`` folder (git-ignored) when the builder starts.
"""

from __future__ import annotations

import inspect
import re
from dataclasses import dataclass, field
from pathlib import Path

# The sections of Gymnasium's env pages, in order, and the card headings that fill them.
GYM_SECTIONS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("Description", ("description",)),
    ("Action Space", ("action space",)),
    ("Observation Space", ("observation space", "observation")),
    ("Rewards", ("rewards", "reward")),
    ("Starting State", ("starting state",)),
    ("Episode End", ("episode end",)),
    ("Arguments", ("arguments",)),
)
"""Gymnasium's sections (Version History comes last, with the registered versions)."""

FAMILY_PAGES: dict[str, tuple[str, str]] = {
    "lift": ("Lift", "Pick the cylinder up and hold it: soft, rigid and torsional fingers, the dense and sparse "
             "rewards, the reach and the gentle (Easy) start."),
    "grip": ("Grip force", "Hold the cylinder with the least squeeze: the squeeze as the action, mass and friction "
             "drawn and not observed, taxels on each pad."),
    "objects": ("Object set", "Grasp a shape drawn per episode from eleven - sphere, boxes, capsule, cone, rod, "
                "elliptic cylinder, pebbles, the cylinder - at a drawn size, mass and friction, its kind and "
                "extents observed: soft, rigid and torsional fingers, the carry and the grip-force tasks."),
    "goal": ("Goal", "Goal-conditioned lift for hindsight experience replay: dict observations and "
             "`compute_reward`."),
}
"""Each family's page name (``envs/<key>``), title and one-line summary, in the order of the index."""

FAMILY_SECTIONS: dict[str, tuple[str, ...]] = {"grip": ("grip-force task",),
                                                "objects": ("object set", "grip-force task")}
"""Sections of the lift card (``SoftGraspEnv``) that belong to some families only (by their
lower-cased headings): those families' pages show them right after the description, the other
pages leave them out."""


@dataclass
class Family:
    key: str
    title: str
    summary: str
    card: type
    ids: list[str] = field(default_factory=list)


# --- the cards -------------------------------------------------------------------------------------


def card_text(cls: type) -> str:
    """``cls``'s docstring, dedented (the env card as written)."""
    return inspect.cleandoc(cls.__doc__ or "")


def split_sections(text: str) -> tuple[str, dict[str, str]]:
    """A card's preamble (before its first ``## `` heading) and its sections by lower-cased heading."""
    parts = re.split(r"^## +(.+?) *$", text, flags=re.M)
    sections = {parts[k].strip().lower(): parts[k + 1].strip() for k in range(1, len(parts), 2)}
    return parts[0].strip(), sections


def _to_myst(text: str) -> str:
    """Docstring markup that Markdown does not know: reST roles become code spans (``:class:`X``` -> `X`)."""
    text = re.sub(r":(?:py:)?(?:class|func|meth|data|attr|mod|obj):`~?([^`]+)`", r"`\1`", text)
    return text


def fill_arguments(section: str) -> str:
    """The Arguments section with the argument table made now from ``EnvArguments``: the
    ``<arguments>`` placeholder, or the table that env.py already put in its place, replaced."""
    from softgrasp_env import arguments

    table = arguments.argument_table()
    if "<arguments>" in section:
        return section.replace("<arguments>", table)
    lines = section.splitlines()
    start = next((k for k, line in enumerate(lines) if line.startswith("| Parameter |")), None)
    if start is None:  # a card without the table: put it at the end
        return section + "\n\n" + table
    end = start
    while end < len(lines) and lines[end].startswith("|"):
        end += 1
    return "\n".join(lines[:start] + [table] + lines[end:])


def goal_sections(text: str) -> tuple[str, dict[str, str]]:
    """The goal card's preamble and sections: its ``## `` headings if it has them; else its
    labelled items (``- Observation: ...``, ``- Reward: ...``, ``Extra arguments: ...``) taken as
    those sections and the paragraphs before them as the description."""
    preamble, sections = split_sections(text)
    if sections:
        return preamble, sections
    paragraphs = re.split(r"\n\s*\n", text)
    title, description, found = paragraphs[0], [], {}
    label_re = re.compile(r"^-?\s*(Observation|Reward|Extra arguments):\s*", re.S)
    for para in paragraphs[1:]:
        # a bullet list may hold several labelled items
        items = re.split(r"\n(?=- )", para) if para.lstrip().startswith("- ") else [para]
        for item in items:
            m = label_re.match(item.strip())
            if m is None:
                description.append(item)
                continue
            key = {"observation": "observation space", "reward": "rewards", "extra arguments": "arguments"}[
                m.group(1).lower()]
            body = re.sub(r"\n\s+", "\n", item.strip()[m.end():])
            found[key] = (found.get(key, "") + "\n\n" + body).strip()
    found["description"] = "\n\n".join(description).strip()
    return title, found


# --- the registry ----------------------------------------------------------------------------------


def family_of(env_id: str) -> str:
    """The family an id is in, from its registration: the goal env class; the object set
    (``registration.OBJECT_SET``); the grip-force task (the squeeze as the action,
    ``finger_action="force"``, whatever its charge: each version of the task sets its own);
    else the lift family."""
    import gymnasium as gym

    from softgrasp_env import env as env_module
    from softgrasp_env import registration

    spec = gym.spec(env_id)
    cls = spec.entry_point if isinstance(spec.entry_point, type) else None
    if cls is None:
        module, _, name = str(spec.entry_point).partition(":")
        cls = getattr(env_module, name, None) if module == env_module.__name__ else None
    if cls is not None and issubclass(cls, env_module.SoftGraspGoalEnv):
        return "goal"
    if spec.kwargs.get("object") == registration.OBJECT_SET:
        return "objects"
    if spec.kwargs.get("finger_action") == "force":
        return "grip"
    return "lift"


def families() -> dict[str, Family]:
    """Every registered id (``ENV_IDS``) in its family, the families in page order."""
    from softgrasp_env import env as env_module
    from softgrasp_env import registration

    out = {key: Family(key, title, summary, env_module.SoftGraspGoalEnv if key == "goal" else env_module.SoftGraspEnv)
           for key, (title, summary) in FAMILY_PAGES.items()}
    for env_id in registration.ENV_IDS:
        out[family_of(env_id)].ids.append(env_id)
    return {k: f for k, f in out.items() if f.ids}


def split_id(env_id: str) -> tuple[str, str]:
    """``"SoftGrasp-v3"`` -> ``("SoftGrasp", "v3")``."""
    name, _, version = env_id.rpartition("-")
    return name, version


def env_plan(env_id: str):
    """The ``EnvPlan`` of the arguments an id's env is made with (without making the env: no physics
    is built)."""
    import gymnasium as gym

    from softgrasp_env.arguments import EnvArguments, EnvPlan

    kwargs = dict(gym.spec(env_id).kwargs)
    if family_of(env_id) == "goal":  # SoftGraspGoalEnv's own keywords, and what it passes on
        for name in goal_parameters():
            kwargs.pop(name, None)
        kwargs.update(carry=False, reward_type="sparse")
    return EnvPlan.of(EnvArguments.from_kwargs(**kwargs))


def goal_parameters() -> dict[str, inspect.Parameter]:
    """SoftGraspGoalEnv's own keyword arguments (beyond EnvArguments'), from its signature."""
    from softgrasp_env.env import SoftGraspGoalEnv

    params = inspect.signature(SoftGraspGoalEnv.__init__).parameters
    return {n: p for n, p in params.items() if p.kind is inspect.Parameter.KEYWORD_ONLY}


# --- rendering -------------------------------------------------------------------------------------


def _code(value: object) -> str:
    return f"`{value!r}`".replace("|", "\\|")


def _ids_table(fam: Family) -> str:
    import gymnasium as gym

    rows = ["| id | `gym.make` keywords (beyond the defaults) | observation |", "|---|---|---|"]
    for env_id in fam.ids:
        kwargs = ", ".join(f"`{k}={v!r}`" for k, v in gym.spec(env_id).kwargs.items())
        n = len(env_plan(env_id).obs_names)
        obs = (f"`Dict(observation=Box({n}), achieved_goal=Box(3), desired_goal=Box(3))`" if fam.key == "goal"
               else f"`Box({n})`")
        rows.append(f"| `{env_id}` | {kwargs} | {obs} |")
    return "\n".join(rows)


def _summary_table(fam: Family) -> str:
    import gymnasium as gym

    spec = gym.spec(fam.ids[0])
    sizes = sorted({len(env_plan(i).obs_names) for i in fam.ids})
    obs = " or ".join(f"`Box(low, high, ({n},), float32)`" for n in sizes)
    if fam.key == "goal":
        obs = f"`Dict(observation={obs.strip('`')}, achieved_goal=Box(3), desired_goal=Box(3))`"
    ids = ", ".join(f"`{i}`" for i in fam.ids)
    return "\n".join([
        "| | |", "|---|---|",
        "| Action Space | `Box(-1.0, 1.0, (4,), float32)` |",
        f"| Observation Space | {obs} |",
        f"| Ids | {ids} |",
        f"| Time limit | {spec.max_episode_steps} steps |",
        f"| import | `gymnasium.make(\"{fam.ids[0]}\")` after `import softgrasp_env` |",
    ])  # fmt: skip


def _group_of(name: str) -> str:
    from softgrasp_env.observation import OBS_GROUPS, TACTILE_PREFIX

    for group, members in OBS_GROUPS.items():
        if name in members:
            return group
    return "tactile" if name.startswith(TACTILE_PREFIX) else ""


def _observation_entries(fam: Family) -> str:
    """Every id's observation entries by index: one table per distinct observation, the taxels
    one row per taxel (its channels in the row)."""
    from softgrasp_env.observation import TACTILE_PREFIX

    layouts: dict[tuple[str, ...], list[str]] = {}
    for env_id in fam.ids:
        layouts.setdefault(env_plan(env_id).obs_names, []).append(env_id)
    out = ["### Observation entries by id",
           "Generated from each id's arguments (`env.obs_names`); the groups are "
           "`softgrasp_env.observation.OBS_GROUPS`" + (" (the goal ids: the `observation` entry)." if fam.key == "goal"
                                                       else ".")]  # fmt: skip
    for names, ids in layouts.items():
        out.append(f"**{', '.join(f'`{i}`' for i in ids)}**: {len(names)} entries")
        rows = ["| index | name | group |", "|---|---|---|"]
        k = 0
        while k < len(names):
            name = names[k]
            if name.startswith(TACTILE_PREFIX):
                stem = "_".join(name.split("_")[:4])  # tactile_<side>_r<row>_c<col>
                j = k
                while j < len(names) and names[j].startswith(stem + "_"):
                    j += 1
                cell = ", ".join(f"`{n}`" for n in names[k:j])
                rows.append(f"| {k}-{j - 1} | {cell} | tactile |")
                k = j
            else:
                rows.append(f"| {k} | `{name}` | {_group_of(name)} |")
                k += 1
        out.append("\n".join(rows))
    return "\n\n".join(out)


def _goal_arguments_table() -> str:
    rows = ["| Parameter | Default |", "|---|---|"]
    for name, p in goal_parameters().items():
        rows.append(f"| `{name}` | {_code(p.default)} |")
    return "\n".join(rows)


def _version_history(fam: Family, base_history: str) -> str:
    names: dict[str, list[str]] = {}
    for env_id in fam.ids:
        name, version = split_id(env_id)
        names.setdefault(name, []).append(version)
    lines = ["Registered in this release (`softgrasp_env.registration.ENV_IDS`):", ""]
    lines += [f"- `{name}`: {', '.join(sorted(versions, reverse=True))}" for name, versions in names.items()]
    return "\n".join(lines) + "\n\nFrom the card:\n\n" + base_history


def render_family(fam: Family) -> str:
    """The Markdown page of one family."""
    from softgrasp_env.env import SoftGraspEnv

    base_pre, base = split_sections(card_text(SoftGraspEnv))
    base["arguments"] = fill_arguments(base.get("arguments", "<arguments>"))
    gym_keys = {a for _, keys in GYM_SECTIONS for a in keys}
    family_sections = {name for names in FAMILY_SECTIONS.values() for name in names}
    if fam.key == "goal":
        goal_pre, goal = goal_sections(card_text(fam.card))
        own = {"description": (goal_pre + "\n\n" + goal.get("description", "")).strip()}
        for _, keys in GYM_SECTIONS[1:]:  # the description is the preamble and its own section, above
            text = next((goal[k] for k in keys if k in goal), None)
            if text is not None:
                own[keys[0]] = text
        own["arguments"] = (own.get("arguments", "") + "\n\n" + _goal_arguments_table()).strip()
        # what the goal card leaves to the lift card ("as SoftGraspEnv") follows its own text; its
        # reward replaces the lift card's
        inherit = "The lift family's card (`SoftGraspEnv`), which this env extends:"
        sections = {}
        for _, keys in GYM_SECTIONS:
            key, lift = keys[0], base.get(keys[0], "")
            if key == "rewards":
                sections[key] = own.get(key, lift)
            elif own.get(key):
                sections[key] = f"{own[key]}\n\n{inherit}\n\n{lift}"
            else:
                sections[key] = lift
        rest = {k: v for k, v in goal.items() if k not in gym_keys and k != "version history"}
        history = goal.get("version history", base.get("version history", ""))
    else:
        sections = dict(base)
        rest = {k: v for k, v in base.items() if k not in gym_keys and k != "version history"
                and k not in family_sections}  # fmt: skip
        history = base.get("version history", "")
        own = {"description": base_pre}
    out = [f"# {fam.title} family", "",
           "<!-- Generated by docs/_ext/envpages.py from the env cards and the registry: edit the code, "
           "not this page. -->", "",
           f"{fam.summary}", "", _summary_table(fam), ""]  # fmt: skip
    if fam.key != "goal" and own["description"]:
        out += [own["description"], ""]
    for family_section in FAMILY_SECTIONS.get(fam.key, ()):
        if family_section in sections:
            out += [f"## {family_section[:1].upper()}{family_section[1:]}", "", sections[family_section], ""]
    for title, keys in GYM_SECTIONS:
        body = next((sections[k] for k in keys if k in sections), "")
        out += [f"## {title}", "", body, ""]
        if title == "Observation Space":
            out += [_observation_entries(fam), ""]
        if title == "Arguments":
            out += ["### Registered ids", "", _ids_table(fam), ""]
    for title, body in rest.items():
        out += [f"## {title[:1].upper()}{title[1:]}", "", body, ""]
    out += ["## Version History", "", _version_history(fam, history), ""]
    return _to_myst("\n".join(out)).rstrip() + "\n"


def render_index(fams: dict[str, Family]) -> str:
    """The envs/ index: every family, every id."""
    lines = ["# Environments", "",
             "<!-- Generated by docs/_ext/envpages.py: edit the code, not this page. -->", "",
             "Every id registered by `import softgrasp_env`, one page per family; each page is generated "
             "from the env card (the class docstring) and the registry, so it says what the code does.", "",
             "| family | ids | |", "|---|---|---|"]  # fmt: skip
    for fam in fams.values():
        lines.append(f"| [{fam.title}]({fam.key}.md) | {', '.join(f'`{i}`' for i in fam.ids)} | {fam.summary} |")
    lines += ["", "```{toctree}", ":hidden:", "", *[fam.key for fam in fams.values()], "```", ""]
    return "\n".join(lines)


def render_pages() -> dict[str, str]:
    """Every page of envs/ by file name."""
    fams = families()
    pages = {"index.md": render_index(fams)}
    pages.update({f"{fam.key}.md": render_family(fam) for fam in fams.values()})
    return pages


def write_pages(folder: Path) -> list[Path]:
    """Write the pages into ``folder`` (made if missing); files whose text is unchanged are not
    touched (Sphinx would rebuild them), pages of families that are gone are removed."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    pages = render_pages()
    written = []
    for name, text in pages.items():
        path = folder / name
        if not path.exists() or path.read_text(encoding="utf-8") != text:
            path.write_text(text, encoding="utf-8")
        written.append(path)
    for stale in folder.glob("*.md"):
        if stale.name not in pages:
            stale.unlink()
    return written


def _builder_inited(app) -> None:
    write_pages(Path(app.srcdir) / "envs")


def setup(app):
    app.connect("builder-inited", _builder_inited)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
