"""Sources of the explicit scheme's generated loop (:mod:`softcell.engine.compiled`), read as
text and never imported: the names they use without defining are bound by the code that
compiles them."""
