"""The paper scenario under each contact option (docs/model.md section 3.6), in the paper's
setup: ``drive_rattle_cosim.contact_laws`` (its table is in docs/model.md, written by
``python -m drive_rattle_cosim.model_doc --update``).

    python benchmarks/contact_laws.py [--stop-time 11] [--transient 1] [--window 2]
        [--out out/contact_laws.md]
"""

from __future__ import annotations

from drive_rattle_cosim.contact_laws import main

if __name__ == "__main__":
    raise SystemExit(main())
