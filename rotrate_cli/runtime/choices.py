"""The names the command line offers as choices, kept apart from the stages that use them so
that ``rotrate --help`` needs none of the heavy libraries (OpenCV, pandas, SciPy)."""

#: The rate estimators: ours (a sinusoid fit per track) and the reference paper's.
METHODS = ("fit", "paper")
#: The report formats.
FORMATS = ("table", "csv", "json")
#: What ``rotrate synth`` renders.
SHAPES = ("box", "cylinder", "sphere")
PROJECTIONS = ("orthographic", "perspective")
