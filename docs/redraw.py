"""Draw the committed study figures again from their records, without running the studies.

Each page's figure is drawn by its study from the values in the record beside it
(``<name>.json``), so a change of how figures look needs no new runs::

    python docs/redraw.py

The records stay as they are; only the PNG files beside them are written.
"""

from pathlib import Path

from softcell.studies import studies

HERE = Path(__file__).parent

#: Each committed record and the figure drawn from it.
RECORDS = {
    "strategies/strategies.json": "strategies/strategies.png",
    "assemblies/crowding.json": "assemblies/crowding.png",
    "assemblies/constriction.json": "assemblies/constriction.png",
    "bots/bots.json": "bots/bots.png",
    "bots/bots_medium.json": "bots/bots_medium.png",
}


def main() -> None:
    import json

    from softcell.studies.figures import friction_figures
    from softcell.studies.friction_and_arena import FREE_LONG, VARIANTS

    every = studies()
    for record, figure in RECORDS.items():
        name = json.loads((HERE / record).read_text(encoding="utf-8"))["study"]
        every[name].redraw(HERE / record, HERE / figure)
        print(f"{figure} from {record}")
    # `softcell beyond`'s record: the static-friction variants and the arena.
    results = json.loads((HERE / "beyond" / "beyond.json").read_text(encoding="utf-8"))
    for name in friction_figures(HERE / "beyond", VARIANTS, results, FREE_LONG[1]):
        print(f"beyond/{name} from beyond/beyond.json")


if __name__ == "__main__":
    main()
