"""satchain.scene"""
