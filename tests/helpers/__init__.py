"""Code the tests share: mesh builders, oracles and fixtures' data (importable as ``helpers``)."""
