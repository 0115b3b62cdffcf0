"""sensfw: which parameters of a nonlinear multibody model matter, and does the model agree
with the rig?

The data path follows the folders: study -> designs -> runs -> models -> signal + scorers ->
surrogates + analysis -> report; measured data -> measure -> report.
"""

__version__ = "0.1.0"
