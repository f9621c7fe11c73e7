"""satchain.engine"""
