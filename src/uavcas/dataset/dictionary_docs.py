"""docs/formats.md's generated data-dictionary section, from the dictionary (`dataset.dictionary`)
and the Arrow schemas (`dataset.parquet`). Its own module because the Parquet writer reads the
dictionary for field metadata: the dictionary itself must not import the writer.

    python -m uavcas.dataset.dictionary_docs docs/formats.md   # rewrite the section
"""

from __future__ import annotations

from uavcas import schema as s
from uavcas.flows.standards import DEFAULT_STANDARD, standards
from uavcas.views import DEFAULT_VIEW, view

from .dictionary import columns, markdown_table
from .parquet import arrow_schema


def markdown() -> str:
    """docs/formats.md's generated section: the columns of a flow dataset of the default standard
    with context, every other standard's features, and the window-host view's own columns."""
    table, default = markdown_table, DEFAULT_STANDARD
    others = [std for std in standards() if std.name != default]
    flow_view, episode_view = view(DEFAULT_VIEW), view(s.EPISODE_VIEW)
    flows = columns(arrow_schema(default, context=True), default, flow_view)
    flow_names = {c.name for c in flows}
    summaries = set(s.EPISODE_CONTEXT_FEATURES) - set(s.EPISODE_ROUTE_FEATURES)  # said in one sentence below
    episode = [c for c in columns(arrow_schema(default, context=True, view=s.EPISODE_VIEW), default, episode_view)
               if (c.name not in flow_names or c.name == "packets") and c.name not in summaries]
    out = ["<!-- generated: python -m uavcas.dataset.dictionary_docs docs/formats.md (tests/dataset/test_dictionary.py "
           "checks it) -->",
           "", f"Flow datasets (`{default}` standard, with the context columns):", "", *table(flows), ""]
    for std in others:
        own = [c for c in columns(arrow_schema(std.name), std.name, flow_view) if c.name in std.units]
        out += [f"The `{std.name}` standard's {len(std.columns)} features (in place of the `{default}` ones):", "",
                *table(own), ""]
        episode += [c for c in columns(arrow_schema(std.name, view=s.EPISODE_VIEW), std.name, episode_view)
                    if c.name not in {e.name for e in episode} and c.name not in flow_names]
    out += ["The window-host view's own columns (identity, axes, truth and labels as for flows; each context column "
            "`ctx_<name>` as `ctx_<name>_mean` and `ctx_<name>_max` over the episode's flows, same unit):", "",
            *table(episode)]
    return "\n".join(out) + "\n"


DOCS_BEGIN, DOCS_END = "<!-- BEGIN data dictionary -->\n", "<!-- END data dictionary -->"


def with_docs_section(text: str) -> str:
    """`text` (docs/formats.md) with the section between the markers replaced by `markdown()`."""
    a, b = text.index(DOCS_BEGIN) + len(DOCS_BEGIN), text.index(DOCS_END)
    return text[:a] + markdown() + text[b:]


if __name__ == "__main__":  # python -m uavcas.dataset.dictionary_docs docs/formats.md: rewrite its section
    import sys
    from pathlib import Path

    doc = Path(sys.argv[1])
    doc.write_text(with_docs_section(doc.read_text()))
