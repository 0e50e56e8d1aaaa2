"""A MaterialX document read with the standard libraries imported and validated, for
check_export_skin.py (OpenPBR) and check_export_hair.py (chiang_hair_bsdf)."""


def load_validated(path):
    """(document, ok, message) of MaterialX's own doc.validate() on the file at `path`."""
    import MaterialX as mx

    doc = mx.createDocument()
    mx.readFromXmlFile(doc, str(path))
    lib = mx.createDocument()
    mx.loadLibraries(mx.getDefaultDataLibraryFolders(), mx.getDefaultDataSearchPath(), lib)
    doc.importLibrary(lib)
    ok, msg = doc.validate()
    return doc, ok, msg
