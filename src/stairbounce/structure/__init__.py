"""The exact structure of the (e, u) plane: borders, regions and their certification.

One module per concept (issue 36, item 9); the certifier lives here first.
"""

from .certificate import Certificate
from .certify import CertifiedAtlas, certify, certify_box

__all__ = ["Certificate", "CertifiedAtlas", "certify", "certify_box"]
