"""The paper, reproduced: the whole run, the experiment's pipeline (film, track, analyse), the
findings beside ours, the paper's figures, the report and the calibrations."""
