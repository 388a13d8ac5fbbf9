"""A sphinx-gallery image scraper for contactqp's charts.

contactqp draws on matplotlib Figures of its own, never through pyplot, so the default scraper
(which asks pyplot for open figures) sees none. This one shows every Figure (or the Figure of
an Axes) that a code block left in the example's variables and that was not shown before.
"""

from sphinx_gallery.scrapers import figure_rst

_shown: dict[str, set[int]] = {}


def _figures(variables: dict) -> list:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    found = []
    for value in list(variables.values()):
        figure = value.figure if isinstance(value, Axes) else value
        if isinstance(figure, Figure) and all(figure is not f for f in found):
            found.append(figure)
    return found


def scrape_figures(block, block_vars, gallery_conf, **kwargs):
    """Save the block's new Figures as images and return the reST that shows them.

    Parameters
    ----------
    block : tuple
        The code block sphinx-gallery ran.
    block_vars : dict
        Its variables; ``example_globals`` holds the example's globals.
    gallery_conf : dict
        sphinx-gallery's configuration.
    **kwargs
        Unused (the scraper interface).

    Returns
    -------
    str
        reST showing the images.
    """
    shown = _shown.setdefault(block_vars["src_file"], set())
    paths = []
    for figure, path in zip(
            [f for f in _figures(block_vars["example_globals"]) if id(f) not in shown],
            block_vars["image_path_iterator"]):
        shown.add(id(figure))
        figure.savefig(path, dpi=110)
        paths.append(path)
    return figure_rst(paths, gallery_conf["src_dir"])
