"""The numbers and tables docs/RESULTS.md quotes, each computed from the data files the
evidence wrote (never typed by hand): results_doc.py puts them into the template, and the
suite checks that RESULTS.md is the template rendered from docs/results/.

Each fact is a function of the loaded data ({section: its JSON}) returning text; each
section's facts are in its own module, named by the section's prefix ("maps.", "rate.", ...),
and fact_text.py writes the units.
"""

import admittance_facts
import effort_facts
import firmware_facts
import identification_facts
import maps_facts
import rate_facts
import scene_facts
import timing_facts
import zwidth_facts

def total_time(data):
    """The sections' own run times summed, and the modes they ran in."""
    seconds = sum(block["seconds"] for block in data.values())
    modes = sorted({block["mode"] for block in data.values()})
    return f"{seconds:,.0f} s for {len(data)} sections ({', '.join(modes)} mode)"


FACTS = {"evidence.total_time": total_time,
         **maps_facts.FACTS, **rate_facts.FACTS, **identification_facts.FACTS,
         **zwidth_facts.FACTS, **scene_facts.FACTS,
         **effort_facts.FACTS, **admittance_facts.FACTS, **firmware_facts.FACTS,
         **timing_facts.FACTS}
