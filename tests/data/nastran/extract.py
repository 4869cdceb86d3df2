"""Regenerate the .npz extracts of the OP2 files here (needs pyNastran; run from this folder).

The tests read the extracts, so that they run without pyNastran; where pyNastran is installed,
tests/appendages/test_nastran.py also checks that the extracts equal a fresh read of the OP2 files.

    python extract.py
"""

import numpy as np

from appendages import nastran

#: CBAR element 1 (grids 1-2, at the root) of beam_modes: its internal forces at end A.
ROOT_ELEMENT = 1


def main() -> None:
    for name in ("beam_modes", "mode_solid_shell_bar"):
        nastran.read_op2(f"{name}.op2").save(f"{name}.npz")
    from pyNastran.op2.op2 import read_op2

    forces = read_op2("beam_modes.op2", debug=None, log=None).op2_results.force.cbar_force[1]
    element = list(forces.element).index(ROOT_ELEMENT)
    np.savez("beam_modes_root_element.npz", forces=np.asarray(forces.data[:, element, :]),
             headers=np.array(forces.get_headers()))


if __name__ == "__main__":
    main()
