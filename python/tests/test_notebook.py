"""examples/kardia.ipynb runs to the end without a cell error (nbclient, the venv's kernel)."""

import pathlib

from conftest import need

NOTEBOOK = pathlib.Path(__file__).resolve().parents[2] / "examples" / "kardia.ipynb"


def test_the_example_notebook_runs():
    nbformat = need("nbformat")
    nbclient = need("nbclient")
    notebook = nbformat.read(NOTEBOOK, as_version=4)
    client = nbclient.NotebookClient(
        notebook, timeout=600, kernel_name="python3", resources={"metadata": {"path": str(NOTEBOOK.parent)}}
    )
    client.execute()  # raises CellExecutionError on any cell's error
    outputs = [o for cell in notebook.cells if cell.cell_type == "code" for o in cell.get("outputs", [])]
    assert any("image/png" in o.get("data", {}) for o in outputs)
