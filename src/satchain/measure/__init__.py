"""satchain.measure"""
